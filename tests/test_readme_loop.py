"""README's "The whole loop", run as written: every command exits 0 and writes its files."""
import csv
import re
import shlex
from pathlib import Path

from doe_calib.cli import main

ROOT = Path(__file__).resolve().parents[1]
OUTPUTS = ("--out", "--truth-out", "--program-out")


def loop_commands() -> list[str]:
    """The lines of the section's bash block, in order."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## The whole loop", 1)[1].split("\n## ", 1)[0]
    block = re.search(r"```bash\n(.*?)```", section, re.S).group(1)
    return [line.strip() for line in block.splitlines() if line.strip()]


def _expand(line: str, variables: dict) -> str:
    return re.sub(r"\$(\w+)", lambda m: variables[m.group(1)], line)


def test_readme_loop_runs_in_order(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    variables, ran = {}, []
    for line in loop_commands():
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
