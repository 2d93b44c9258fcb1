"""README's "The whole loop", run as written: every command exits 0 and writes its files.

:func:`loop_commands` and :func:`run_loop` run any section's block (tests/
test_readme_loop_without_tracker.py runs "The loop without a tracker")."""
import csv
import re
import shlex
from pathlib import Path

from doe_calib.cli import main

ROOT = Path(__file__).resolve().parents[1]
OUTPUTS = ("--out", "--truth-out", "--program-out")


def section_text(title: str) -> str:
    """The README's section ``## title``, up to the next section."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return text.split(f"## {title}\n", 1)[1].split("\n## ", 1)[0]


def loop_commands(title: str = "The whole loop") -> list[str]:
    """The lines of the bash block of the README's section ``## title``, in order."""
    block = re.search(r"```bash\n(.*?)```", section_text(title), re.S).group(1)
    return [line.strip() for line in block.splitlines() if line.strip()]


def _expand(line: str, variables: dict) -> str:
    return re.sub(r"\$(\w+)", lambda m: variables[m.group(1)], line)


def run_loop(title: str, tmp_path, monkeypatch, capsys=None) -> tuple[list, list]:
    """Run the block of the README's section ``## title`` in ``tmp_path``: every command
    exits 0 and writes its outputs. Returns each command's name and, with ``capsys``, what
    each printed (stdout and stderr)."""
    monkeypatch.chdir(tmp_path)
    variables, ran, printed = {}, [], []
    for line in loop_commands(title):
        assignment = re.fullmatch(r"(\w+)=(\S+)", line)
        if assignment:   # paths are the repository's (the README runs from its root)
            name, value = assignment.groups()
            variables[name] = str(ROOT / value) if (ROOT / value).exists() else value
            continue
        argv = shlex.split(_expand(line, variables))
        assert argv[0] == "doe-calib", line
        assert main(argv[1:]) == 0, line
        for flag, path in zip(argv, argv[1:]):
            if flag in OUTPUTS:
                out = Path(path)
                assert out.is_file() or (out.is_dir() and any(out.iterdir())), line
        ran.append(argv[1])
        if capsys is not None:
            said = capsys.readouterr()
            printed.append(said.out + said.err)
    return ran, printed


def test_readme_loop_runs_in_order(tmp_path, monkeypatch):
    ran, _ = run_loop("The whole loop", tmp_path, monkeypatch)
    assert ran == ["design", "export", "simulate", "simulate", "identify", "diagnose", "refine",
                   "export", "compensate", "export-urdf", "iso9283", "export", "simulate",
                   "compensate", "simulate", "iso9283"]
    for name in ("design.csv", "program/doe_calib.src", "program/doe_calib.dat", "truth.json",
                 "refined_refine.json", "compensated/compensated.src", "kr270_calibrated.yaml"):
        assert (tmp_path / name).is_file(), name
    # refine found the hidden A2 compensator
    assert "compliance_by_angle(j2" in (tmp_path / "refined.json").read_text()
    with open(tmp_path / "compensated.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    # every row reached, or named with its reason (a pose at a joint limit cannot move on)
    missed = [r for r in rows if r["converged"] != "true"]
    assert len(rows) == 30 and len(missed) <= 3, missed
    assert all("at the limit of" in r["note"] for r in missed), missed
    # the acceptance test: compensation brings every pose's AP from mm to the noise's scale
    import json
    before, after = json.loads((tmp_path / "iso_report.json").read_text())["campaigns"]
    for pose in ("P1", "P2", "P3", "P4", "P5"):
        assert before["poses"][pose]["AP_mm"] > 1.0 > 0.1 > after["poses"][pose]["AP_mm"], pose
        assert after["poses"][pose]["RP_mm"] < 0.2 and after["poses"][pose]["n"] == 30, pose
