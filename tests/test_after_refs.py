"""A creature task's ``after`` (earlier stages' controller files): resolved against
the record that names it, and a stage starting after itself is one error line."""
import json
import shutil
from pathlib import Path

from gpmotion.cli import main
from tests.cli_checks import one_line_error

DATA = Path(__file__).parent / "data"


def _with_after(src: Path, dst: Path, after: str) -> Path:
    rec = json.loads(src.read_text())
    rec["params"]["after"] = after
    dst.write_text(json.dumps(rec))
    return dst


def test_a_stage_after_itself_is_one_line(tmp_path, capsys):
    _with_after(DATA / "rex_walk_v1_lunge.json", tmp_path / "self.json", "self.json")
    assert main(["replay", str(tmp_path / "self.json")]) == 2
    one_line_error(capsys, "cycle")


def test_two_stages_after_each_other_are_one_line(tmp_path, capsys):
    _with_after(DATA / "rex_walk_v1_lunge.json", tmp_path / "a.json", "b.json")
    _with_after(DATA / "rex_walk_v1_lunge.json", tmp_path / "b.json", "a.json")
    assert main(["replay", str(tmp_path / "a.json")]) == 2
    one_line_error(capsys, "cycle")


def test_after_resolves_beside_the_record_not_in_the_current_folder(tmp_path, capsys,
                                                                   monkeypatch):
    d = tmp_path / "stages"
    d.mkdir()
    shutil.copy(DATA / "rex_turn_v3" / "walk.json", d / "walk.json")
    _with_after(DATA / "rex_turn_v3" / "turn.json", d / "turn.json", "walk.json")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    assert main(["replay", str(d / "turn.json"), "--json"]) == 0, capsys.readouterr().err
