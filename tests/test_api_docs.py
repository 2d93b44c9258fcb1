"""Every example in the API docs (docs/api/*.md) runs, page by page, as written."""
import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs" / "api"
PAGES = sorted(DOCS.glob("*.md"))


def page_code(page: Path) -> str:
    """The page's ```python blocks joined in order (each page is one session)."""
    return "\n".join(re.findall(r"^```python\n(.*?)^```", page.read_text(encoding="utf-8"),
                                re.S | re.M))


def test_there_are_pages_with_examples():
    names = {p.stem for p in PAGES}
    assert {"index", "model", "identify", "design", "diagnose", "compensate",
            "export"} <= names
    assert all(page_code(p) for p in PAGES if p.stem != "index")


@pytest.mark.parametrize("page", [p for p in PAGES if p.stem != "index"], ids=lambda p: p.stem)
def test_page_examples_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = compile(page_code(page), str(page), "exec")
    exec(code, {"__name__": f"docs_{page.stem}"})  # noqa: S102 - the docs are ours


def test_index_lists_every_public_name():
    import doe_calib

    text = (DOCS / "index.md").read_text(encoding="utf-8")
    missing = [n for n in doe_calib.__all__ if f"`{n}`" not in text]
    assert not missing, f"docs/api/index.md does not list {missing}"
    listed = set(re.findall(r"^\| `(\w+)` \|", text, re.M))
    extra = listed - set(doe_calib.__all__)
    assert not extra, f"listed but not public: {extra}"

