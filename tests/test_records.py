"""records.py: atomic writes survive a failing writer, run directories are
never clobbered, the log survives a torn line, loading refuses anything not
ours with one FormatError line, and RNG states round-trip exactly."""
import json
import os
import random

import numpy as np
import pytest
from hypothesis import given, settings, HealthCheck
from hypothesis import strategies as st

from gpmotion import records
from gpmotion.records import (ConfigError, FormatError, RunDirError, atomic_write_json,
                              atomic_write_text, read_json)
from gpmotion.records import display_path
from gpmotion.rundir import RunDir


def leftovers(directory):
    return [p.name for p in directory.iterdir() if p.name.endswith(".tmp")]


def ours(kind="checkpoint", **extra):
    return {"format": f"gpmotion-{kind}", "version": 1, **extra}


# ------------------------------------------------------------ atomic writes

def test_atomic_write_json_roundtrip_with_numpy(tmp_path):
    p = tmp_path / "a.json"
    obj = ours(arr=np.arange(3), x=np.float32(1.5), n=np.int64(7), t=(1, 2),
               big=2**100, s=np.str_("é"))
    atomic_write_json(p, obj)
    back = read_json(p, kind="checkpoint")
    assert back["arr"] == [0, 1, 2] and back["x"] == 1.5 and back["n"] == 7
    assert back["t"] == [1, 2] and back["big"] == 2**100 and back["s"] == "é"
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), np.float64(-np.inf),
                                 np.array([1.0, np.nan])])
def test_non_finite_floats_refused_and_old_file_kept(tmp_path, bad):
    p = tmp_path / "best.json"
    atomic_write_text(p, "old")
    with pytest.raises(ValueError, match=r"\$\.fit"):
        atomic_write_json(p, {"fit": bad})
    assert p.read_text() == "old" and leftovers(tmp_path) == []


def test_unserializable_object_refused(tmp_path):
    with pytest.raises(TypeError, match=r"\$\.f"):
        atomic_write_json(tmp_path / "x.json", {"f": object()})
    with pytest.raises(TypeError):
        atomic_write_json(tmp_path / "x.json", {1: 2})
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("where, error", [(("json", "dumps"), RuntimeError("killed mid-way")),
                                          (("os", "replace"), OSError("power cut"))])
def test_writer_crash_keeps_old_content(tmp_path, monkeypatch, where, error):
    p = tmp_path / "c.json"
    atomic_write_json(p, ours(gen=1))

    def boom(*a, **k):
        raise error
    module, name = where
    monkeypatch.setattr(getattr(records, module), name, boom)
    with pytest.raises(type(error)):
        atomic_write_json(p, ours(gen=2))
    monkeypatch.undo()
    assert read_json(p, kind="checkpoint")["gen"] == 1
    assert leftovers(tmp_path) == []


def test_crash_during_write_keeps_old_content(tmp_path, monkeypatch):
    p = tmp_path / "t.txt"
    atomic_write_text(p, "old")
    real_fsync = os.fsync

    def boom(fd):
        raise OSError("I/O error")
    monkeypatch.setattr(records.os, "fsync", boom)
    with pytest.raises(OSError):
        atomic_write_text(p, "new")
    monkeypatch.setattr(records.os, "fsync", real_fsync)
    assert p.read_text() == "old" and leftovers(tmp_path) == []


# ----------------------------------------------------------------- reading

@pytest.mark.parametrize("text, problem", [
    ('{"format": "gpmotion-checkpoint", "version": 1, "pop": [1, 2', "truncated"),
    ("", "malformed"),
    ("not json at all", "malformed"),
    ("[1, 2, 3]", "JSON object"),
    ('{"format": "gpmotion-best", "version": 1}', "format"),
    ('{"version": 1}', "format"),
    ('{"format": "gpmotion-checkpoint", "version": 2}', "version"),
    ('{"format": "gpmotion-checkpoint", "version": true}', "version"),
    ('{"format": "gpmotion-checkpoint", "version": "1"}', "version"),
    ('{"format": "gpmotion-checkpoint", "version": 1, "x": NaN}', "NaN"),
    ('{"format": "gpmotion-checkpoint", "version": 1, "x": Infinity}', "Infinity"),
    ('{"format": "gpmotion-checkpoint", "version": 1, "version": 1}', "duplicate"),
    ("[" * 100_000, "deep|malformed"),
    ('{"format": "gpmotion-checkpoint", "version": 1, "n": ' + "9" * 5000 + "}", "invalid"),
])
def test_read_json_rejects_with_one_line(tmp_path, text, problem):
    p = tmp_path / "checkpoint.json"
    p.write_text(text)
    with pytest.raises(FormatError) as err:
        read_json(p, kind="checkpoint")
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(str(p))
    assert any(w.lower() in msg.lower() for w in problem.split("|")), msg


def test_read_json_rejects_binary_missing_and_huge(tmp_path):
    p = tmp_path / "c.json"
    p.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(FormatError, match="UTF-8"):
        read_json(p, kind="checkpoint")
    with pytest.raises(FormatError, match="cannot read"):
        read_json(tmp_path / "missing.json", kind="checkpoint")
    with pytest.raises(FormatError, match="cannot read"):
        read_json(tmp_path, kind="checkpoint")  # a directory
    atomic_write_json(p, ours(pad="x" * 1000))
    with pytest.raises(FormatError, match="limit"):
        read_json(p, kind="checkpoint", max_bytes=500)
    huge = tmp_path / "huge.json"
    with open(huge, "wb") as f:  # sparse: cheap to make, over the default cap
        f.truncate(records.DEFAULT_MAX_BYTES + 1)
    with pytest.raises(FormatError, match="limit"):
        read_json(huge, kind="checkpoint")


@settings(max_examples=300, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                   HealthCheck.too_slow])
@given(data=st.binary(max_size=300))
def test_fuzz_bytes_only_raise_format_error(tmp_path, data):
    p = tmp_path / "fuzz.json"
    p.write_bytes(data)
    try:
        read_json(p, kind="checkpoint")
    except FormatError:
        pass


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=10),
    lambda kids: st.lists(kids, max_size=4)
    | st.dictionaries(st.text(max_size=8), kids, max_size=4)
    | st.fixed_dictionaries({"format": st.sampled_from(
        ["gpmotion-checkpoint", "gpmotion-best", None, 1]),
        "version": st.sampled_from([1, 1.0, True, 2, "1", None])}, optional={"x": kids}),
    max_leaves=20)


@settings(max_examples=300, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                   HealthCheck.too_slow])
@given(value=json_values)
def test_fuzz_json_values_only_raise_format_error(tmp_path, value):
    p = tmp_path / "fuzz.json"
    p.write_text(json.dumps(value))  # may include NaN/Infinity literals
    try:
        out = read_json(p, kind="checkpoint")
    except FormatError:
        return
    assert out["format"] == "gpmotion-checkpoint" and type(out["version"]) is int


# ------------------------------------------------------------ config values

@pytest.mark.parametrize("value, kw, expected", [
    (3, dict(lo=1, integer=True), 3),
    ("12", dict(lo=1, integer=True), 12),
    (4.0, dict(lo=1, integer=True), 4),
    (0.5, dict(lo=0, hi=1), 0.5),
    (np.float32(0.25), dict(lo=0, hi=1), 0.25),
    (None, dict(allow_none=True), None),
])
def test_validate_number_accepts(value, kw, expected):
    assert records.validate_number("--x", value, **kw) == expected


def test_validate_number_message():
    with pytest.raises(ConfigError) as err:
        records.validate_number("--generations", -3, lo=1, integer=True)
    assert str(err.value) == "--generations must be an integer ≥ 1, got -3"


@pytest.mark.parametrize("value, kw", [
    (float("nan"), {}), (float("inf"), {}), ("inf", {}), (-1, dict(lo=0)),
    (10**9, dict(hi=10**6)), (2.5, dict(integer=True)), (True, {}),
    ("abc", {}), (None, {}), ([1], {}), ("1e400", {}),
])
def test_validate_number_rejects(value, kw):
    with pytest.raises(ConfigError, match="^--x must be"):
        records.validate_number("--x", value, **kw)


# ------------------------------------------------------------------ RunDir

def test_rundir_fresh_and_records(tmp_path):
    run = RunDir.create(tmp_path / "runs" / "a")
    run.write_config({"seed": 1, "pop": 50})
    assert run.read_config()["seed"] == 1
    run.write_best({"fitness": 0.5, "trees": [["add", "x", 1.0]]})
    assert read_json(run.path / "best.json", kind="best")["fitness"] == 0.5
    run.save_checkpoint({"generation": 3, "rng": records.numpy_rng_state_to_json(
        np.random.default_rng(0))})
    assert run.load_checkpoint()["generation"] == 3
    assert run.checkpoint_path.name == "checkpoint.json"
    assert display_path(run.artifact("curve.png")) == run.path / "curve.png"
    for bad in ["../x", "a/b", "", ".."]:
        with pytest.raises(ValueError):
            run.artifact(bad)
    with pytest.raises(ValueError):
        run.write_best({"format": "gpmotion-checkpoint"})
    with pytest.raises(FormatError):  # a checkpoint is not a best file
        read_json(run.checkpoint_path, kind="best")
    assert leftovers(run.path) == []


def test_rundir_refuses_existing_nonempty(tmp_path):
    d = tmp_path / "run"
    d.mkdir()
    RunDir.create(d)  # empty is fine
    (d / "log.csv").write_text("generation\n1\n")
    with pytest.raises(RunDirError, match="not empty.*--force.*--resume"):
        RunDir.create(d)
    assert (d / "log.csv").read_text() == "generation\n1\n"
    with pytest.raises(RunDirError):
        RunDir.create(d, force=True, resume=True)
    f = tmp_path / "file"
    f.write_text("x")
    with pytest.raises(RunDirError, match="not a directory"):
        RunDir.create(f)
    with pytest.raises(RunDirError, match="cannot write"):
        RunDir.create(f / "sub")  # parent is a file


def test_rundir_force_keeps_backup(tmp_path):
    d = tmp_path / "run"
    first = RunDir.create(d)
    first.log_row({"generation": 0, "best": 1.0})
    first.close()
    run = RunDir.create(d, force=True)
    assert run.backup is not None and run.backup.name.startswith("run.bak-")
    assert (run.backup / "log.csv").read_text() == "generation,best\n0,1.0\n"
    assert [p.name for p in d.iterdir()] == [".lock"]
    (d / "x").write_text("y")
    run.close()
    again = RunDir.create(d, force=True)  # second backup within the same second
    assert again.backup != run.backup and again.backup.exists() and run.backup.exists()


def test_log_rows_and_resume(tmp_path):
    d = tmp_path / "run"
    run = RunDir.create(d)
    run.log_row({"generation": 0, "best": 2.5, "note": "a,b\nc"})
    run.log_row({"generation": 1, "best": np.float64(1.25)})
    with pytest.raises(ValueError, match="not in the header"):
        run.log_row({"generation": 2, "surprise": 1})
    run.close()
    resumed = RunDir.create(d, resume=True)
    resumed.log_row({"generation": 2, "best": 1.0, "note": "r"})
    rows = resumed.read_log()
    assert [r["generation"] for r in rows] == ["0", "1", "2"]
    assert rows[0]["note"] == "a,b c" and rows[1]["note"] == "" and rows[1]["best"] == "1.25"
    assert (d / "log.csv").read_text().count("generation") == 1


def test_resume_drops_torn_last_line(tmp_path):
    d = tmp_path / "run"
    run = RunDir.create(d)
    run.log_row({"generation": 0, "best": 2.0})
    run.log_row({"generation": 1, "best": 1.5})
    with open(d / "log.csv", "a") as f:
        f.write("2,1.2")  # crash before the newline
    assert [r["generation"] for r in run.read_log()] == ["0", "1"]
    run.close()
    resumed = RunDir.create(d, resume=True)
    resumed.log_row({"generation": 2, "best": 1.1})
    assert (d / "log.csv").read_text() == "generation,best\n0,2.0\n1,1.5\n2,1.1\n"


def test_resume_with_torn_header_starts_fresh(tmp_path):
    d = tmp_path / "run"
    d.mkdir()
    (d / "log.csv").write_text("genera")
    run = RunDir.create(d, resume=True)
    run.log_row({"generation": 0})
    assert (d / "log.csv").read_text() == "generation\n0\n"


# ------------------------------------------------------------- RNG states

def test_python_random_state_roundtrip():
    r = random.Random(1234)
    r.gauss(0, 1)  # leaves a cached gauss_next
    saved = json.loads(json.dumps(records.python_random_state_to_json(r.getstate())))
    expected = [r.random() for _ in range(5)] + [r.gauss(0, 1)]
    r2 = random.Random()
    r2.setstate(records.python_random_state_from_json(saved))
    assert [r2.random() for _ in range(5)] + [r2.gauss(0, 1)] == expected


@pytest.mark.parametrize("make", [np.random.default_rng, lambda s: np.random.Generator(
    np.random.MT19937(s)), lambda s: np.random.Generator(np.random.Philox(s)),
    lambda s: np.random.Generator(np.random.SFC64(s))])
def test_numpy_rng_roundtrip(make):
    g = make(42)
    g.random(3)
    g.integers(0, 10, size=1)  # leaves a buffered uint32 on some generators
    saved = json.loads(json.dumps(records.numpy_rng_state_to_json(g)))
    expected = (g.random(4), g.normal(size=3), g.integers(0, 2**40, size=3))
    g2 = records.numpy_rng_from_json(saved)
    got = (g2.random(4), g2.normal(size=3), g2.integers(0, 2**40, size=3))
    for a, b in zip(expected, got):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("bad", [
    None, [], {"bit_generator": "Evil"}, {"bit_generator": "PCG64"},
    {"bit_generator": "PCG64", "state": {"state": "x", "inc": 1}, "has_uint32": 0, "uinteger": 0},
    {"bit_generator": "PCG64", "state": {"state": -1, "inc": 1}, "has_uint32": 0, "uinteger": 0},
    {"bit_generator": "PCG64", "state": {"state": 1.5, "inc": 1}, "has_uint32": 0, "uinteger": 0},
    {"bit_generator": "MT19937", "state": {"key": [1, 2], "pos": 0}},
])
def test_numpy_rng_state_validated(bad):
    with pytest.raises(FormatError):
        records.numpy_rng_from_json(bad)


@pytest.mark.parametrize("bad", [
    None, {"version": 2}, {"version": 3, "internal": [0] * 10, "gauss_next": None},
    {"version": 3, "internal": [2**32] + [0] * 624, "gauss_next": None},
    {"version": 3, "internal": [0] * 624 + [625], "gauss_next": None},
    {"version": 3, "internal": [0] * 625, "gauss_next": "x"},
])
def test_python_random_state_validated(bad):
    with pytest.raises(FormatError):
        records.python_random_state_from_json(bad)


leaf = st.none() | st.booleans() | st.integers(-2**130, 2**130) | st.floats() | st.text(max_size=5)


@settings(max_examples=200, suppress_health_check=[HealthCheck.too_slow])  # a loaded machine
@given(name=st.sampled_from(["PCG64", "PCG64DXSM", "Philox", "SFC64", "MT19937", "x"]),
       inner=st.dictionaries(st.sampled_from(["state", "inc", "key", "pos", "counter",
                                              "buffer_pos"]),
                             leaf | st.lists(leaf, max_size=5), max_size=4),
       has=leaf, uint=leaf)
def test_fuzz_numpy_state_only_raises_format_error(name, inner, has, uint):
    d = {"bit_generator": name, "state": inner, "has_uint32": has, "uinteger": uint}
    try:
        records.numpy_rng_from_json(d)
    except FormatError:
        pass


@settings(max_examples=100, suppress_health_check=[HealthCheck.too_slow])
@given(version=leaf, internal=st.lists(st.integers(-5, 2**33), min_size=620, max_size=630)
       | leaf, gauss=leaf)
def test_fuzz_python_state_only_raises_format_error(version, internal, gauss):
    try:
        state = records.python_random_state_from_json(
            {"version": version, "internal": internal, "gauss_next": gauss})
    except FormatError:
        return
    random.Random().setstate(state)
