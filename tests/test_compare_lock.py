"""`gpmotion compare` writes its tables while the comparison folder is locked: a
second compare on the same folder at that moment is refused (one line, exit 2)
and leaves the first one's files whole."""
import hashlib
from pathlib import Path

import gpmotion.compare as compare_module
from gpmotion.cli import main

ARGV = ["compare", "lamp_hop", "--controllers", "gp,bsr-time", "--seeds", "1", "--budget", "30",
        "--param", "seconds=0.3", "--quiet"]


def _digests(folder: Path) -> dict:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file() and p.name != ".lock"}


def test_a_second_compare_while_the_first_writes_its_tables_is_refused(tmp_path, monkeypatch,
                                                                       capsys):
    out = tmp_path / "cmp"
    real = compare_module.atomic_write_text
    seen = {}

    def write_text(path, text, *a, **k):
        if Path(path).name == "compare.csv" and "code" not in seen:
            seen["code"] = -1                          # the nested compare writes nothing
            before = _digests(out)
            seen["code"] = main(ARGV + ["--out", str(out)])
            seen["err"] = capsys.readouterr().err
            seen["unchanged"] = _digests(out) == before
        return real(path, text, *a, **k)

    monkeypatch.setattr(compare_module, "atomic_write_text", write_text)
    assert main(ARGV + ["--out", str(out)]) == 0
    assert seen["code"] == 2, "a second compare ran while the first was writing its tables"
    lines = seen["err"].strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gpmotion: error:") and "in use" in lines[0]
    assert seen["unchanged"]
    # the first compare's tables are its own, whole: one row per controller
    csv_rows = (out / "compare.csv").read_text().splitlines()
    assert len(csv_rows) == 3                           # the header and one row per controller
    md = (out / "compare.md").read_text()
    assert "30 evaluations per run, 1 seeds" in md
    # and a later compare (the lock released) resumes to the same tables
    first = _digests(out)
    monkeypatch.setattr(compare_module, "atomic_write_text", real)
    assert main(ARGV + ["--out", str(out)]) == 0
    assert (out / "compare.csv").read_text().splitlines() == csv_rows
    assert {k: v for k, v in _digests(out).items() if k.startswith("compare.")} == \
        {k: v for k, v in first.items() if k.startswith("compare.")}
