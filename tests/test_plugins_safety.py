"""A data file never runs code; runs record their plugins by name and digest and move freely.

Each test plants a plugin file that would write a marker file if it were ever
imported, and checks the marker is absent after the command.
"""
from __future__ import annotations

import json
import shutil
import textwrap

import pytest

from gpmotion import plugins
from gpmotion.cli import main

MARKER_PLUGIN = textwrap.dedent('''
    from pathlib import Path
    Path({marker!r}).write_text("plugin code ran")
''')

TASK_PLUGIN = textwrap.dedent('''
    from gpmotion.task import Task, Term, register_task

    @register_task
    class {cls}(Task):
        name = "{name}"
        figure = "lamp"
        params = {{"seconds": 0.3}}
        terms = (Term("low", 1.0, main=True),)

        def measure(self, traj):
            return {{"low": {offset} + 1.0 - traj.site("head_tip")[:, -1, 1]}}
''')

SMALL = ["--population", "6", "--generations", "2", "--quiet", "--no-artifacts"]


def _plant(folder, marker):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "evil.py").write_text(MARKER_PLUGIN.format(marker=str(marker)))
    return folder


def _manifest(folder, modules=(), figures=()):
    (folder / plugins.MANIFEST).write_text(f"modules = {list(modules)!r}\nfigures = {list(figures)!r}\n")
    return folder


def _task_plugin(folder, name, offset="0.0"):
    """A folder with one task module and the manifest naming it."""
    folder.mkdir(parents=True, exist_ok=True)
    cls = "".join(w.title() for w in name.split("_"))
    (folder / f"{name}.py").write_text(TASK_PLUGIN.format(cls=cls, name=name, offset=offset))
    return _manifest(folder, modules=[name])


def _one_line_error(capsys):
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpmotion: error:") and "\n" not in err, err
    return err


@pytest.fixture(scope="module")
def plain_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("plain") / "run"
    assert main(["run", "lamp_hop", "--param", "seconds=0.3", "--out", str(out), *SMALL]) == 0
    return out


def _with_plugins(run_dir, dest, value, where="best"):
    """A copy of ``run_dir`` whose best.json (or config.json) ``plugins`` is ``value``."""
    shutil.copytree(run_dir, dest)
    if where == "best":
        p = dest / "best.json"
        rec = json.loads(p.read_text())
        rec["plugins"] = value
    else:
        p = dest / "config.json"
        rec = json.loads(p.read_text())
        rec["run"]["plugins"] = value
        (dest / "best.json").unlink()
    p.write_text(json.dumps(rec))
    return dest


@pytest.mark.parametrize("how", ["absolute", "dot", "string", "record"])
@pytest.mark.parametrize("command", ["replay", "render", "export"])
def test_best_json_plugins_never_run_code(plain_run, tmp_path, monkeypatch, capsys, how, command):
    marker = tmp_path / "MARKER"
    evil = _plant(tmp_path / "evil", marker)
    value = {"absolute": [str(evil)], "dot": ["."], "string": str(evil),
             "record": [{"name": "evil", "digest": plugins.folder_digest(evil)}]}[how]
    run = _with_plugins(plain_run, tmp_path / "copy", value)
    monkeypatch.chdir(evil)                         # "." would be the planted folder
    capsys.readouterr()
    args = {"replay": ["replay", str(run)],
            "render": ["render", str(run), "-o", str(tmp_path / "f.png")],
            "export": ["export", str(run), "--bvh", str(tmp_path / "m.bvh")]}[command]
    assert main(args) == 2
    err = _one_line_error(capsys)
    assert "plugin" in err
    assert not marker.exists(), "a data file ran plugin code"


@pytest.mark.parametrize("value", [["EVIL"], ["."], "EVIL"])
def test_config_json_plugins_never_run_code_on_resume(plain_run, tmp_path, monkeypatch, capsys, value):
    marker = tmp_path / "MARKER"
    evil = _plant(tmp_path / "evil", marker)
    value = [str(evil) if v == "EVIL" else v for v in value] if isinstance(value, list) else str(evil)
    run = _with_plugins(plain_run, tmp_path / "copy", value, where="config")
    monkeypatch.chdir(evil)
    capsys.readouterr()
    assert main(["resume", str(run), "--quiet"]) == 2
    _one_line_error(capsys)
    assert not marker.exists()


def test_a_string_is_not_a_list_of_folders():
    with pytest.raises(plugins.PluginError, match="must be a list"):
        plugins.require("/some/dir", "best.json")


def test_a_run_with_plugins_moves_and_checks_the_digest(tmp_path, capsys):
    """Made with --plugins, copied elsewhere with its plugin folder moved: replays with --plugins
    at the new place; refuses without it, or with a folder of that name holding other code."""
    src = _task_plugin(tmp_path / "a" / "myplug", "sec_portable_a")
    out = tmp_path / "site1" / "run"
    assert main(["run", "sec_portable_a", "--plugins", str(src), "--out", str(out), *SMALL]) == 0
    best = json.loads((out / "best.json").read_text())
    (need,) = best["plugins"]
    assert need["name"] == "myplug" and need["digest"] == plugins.folder_digest(src)
    assert need["path"] == "../../a/myplug"                 # relative to the run: information only
    cfg = json.loads((out / "config.json").read_text())
    assert cfg["run"]["plugins"] == best["plugins"]

    moved = tmp_path / "site2" / "copy"
    shutil.copytree(out, moved)
    new_home = tmp_path / "elsewhere" / "myplug"
    shutil.copytree(src, new_home)
    shutil.rmtree(src)
    capsys.readouterr()
    assert main(["replay", str(moved), "--json", "--plugins", str(new_home)]) == 0
    replayed = json.loads(capsys.readouterr().out)
    assert replayed["cost"] == best["final_cost"]
    assert main(["export", str(moved), "--bvh", str(tmp_path / "m.bvh"),
                 "--plugins", str(new_home)]) == 0
    assert main(["render", str(moved), "-o", str(tmp_path / "f.png"), "--plugins", str(new_home)]) == 0

    other = _task_plugin(tmp_path / "b" / "myplug", "sec_portable_b", offset="1.0")
    plugins.load_folder(other)                # this process already holds the first copy
    plugins._LOADED.pop(need["digest"])       # as a fresh process given only the other folder
    capsys.readouterr()
    assert main(["replay", str(moved), "--plugins", str(other)]) == 2
    err = _one_line_error(capsys)
    assert "myplug" in err and "differs" in err

    for p in list(plugins._LOADED.values()):  # and a process given no folder at all
        if p["name"] == "myplug":
            plugins._LOADED.pop(p["digest"])
    assert main(["replay", str(moved)]) == 2
    err = _one_line_error(capsys)
    assert "needs plugin 'myplug'" in err and "--plugins" in err


def test_pool_workers_get_plugin_code_without_a_shared_folder(tmp_path):
    """Process-pool workers rebuild a plugin task from sources the run ships (no path)."""
    from gpmotion.inprocess import InProcessEvaluator
    from gpmotion.evaluators import ProcessPoolEvaluator
    from gpmotion.families import make_family
    from gpmotion.task import get_task
    import numpy as np
    folder = _task_plugin(tmp_path / "shipped", "sec_shipped_task")
    rec = plugins.load_folder(folder)
    task = get_task("sec_shipped_task")
    fam = make_family("bsr-time", task)
    rng = np.random.default_rng(0)
    pop = [fam.random(rng) for _ in range(6)]
    ref = InProcessEvaluator(task, fam).evaluate(pop)
    with ProcessPoolEvaluator(task, fam, workers=2, plugins=[rec]) as ev:
        shutil.rmtree(folder)                 # workers cannot read it: they use the shipped copy
        got = ev.evaluate(pop)
    assert got.costs.tobytes() == ref.costs.tobytes()


def test_shipped_sources_are_checked_against_their_digest():
    bad = {"name": "x", "digest": "0" * 64, "files": {"x.py": "raise SystemExit"}}
    with pytest.raises(plugins.PluginError, match="do not match"):
        plugins.install_sources([bad])
    bad = {"name": "x", "digest": plugins._digest_of([("../x.py", b"")]), "files": {"../x.py": ""}}
    with pytest.raises(plugins.PluginError, match="bad file name"):
        plugins.install_sources([bad])


def test_installed_entry_points_load_and_are_recorded(tmp_path, monkeypatch):
    """A package declaring a ``gpmotion.plugins`` entry point is loaded (as Gymnasium's
    load_plugin_envs) and recorded with its digest."""
    (tmp_path / "sec_ep_mod.py").write_text(TASK_PLUGIN.format(cls="SecEpTask", name="sec_ep_task",
                                                               offset="0.0"))
    info = tmp_path / "sec_ep_pkg-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: sec-ep-pkg\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[gpmotion.plugins]\nsec_ep = sec_ep_mod\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    records = plugins.activate([])
    (rec,) = [r for r in records if r["name"] == "sec_ep"]
    assert rec["entry_point"] == "sec_ep_mod" and rec["distribution"] == "sec-ep-pkg==1.0"
    from gpmotion.task import task_names
    assert "sec_ep_task" in task_names()
    assert plugins.require([rec], "best.json") == [rec]


def test_one_loader_for_primitives_tasks_and_figures(tmp_path, capsys):
    """A plugin folder's TOML figures register under their file name, with the folder's digest
    covering them (a changed figure is changed code for a run)."""
    folder = tmp_path / "figs"
    folder.mkdir()
    (folder / "sec_stiff_lamp.toml").write_text('extends = "lamp"\nname = "sec_stiff_lamp"\n'
                                                '[[joints]]\nname = "elbow"\nkp = 400.0\n')
    _manifest(folder, figures=["sec_stiff_lamp"])
    before = plugins.folder_digest(folder)
    assert main(["render", "--figure", "sec_stiff_lamp", "--seconds", "0.1", "-o",
                 str(tmp_path / "f.png"), "--plugins", str(folder)]) == 0
    from gpmotion import figure_names
    assert "sec_stiff_lamp" in figure_names()
    (folder / "sec_stiff_lamp.toml").write_text((folder / "sec_stiff_lamp.toml").read_text() + "\n")
    assert plugins.folder_digest(folder) != before


def test_a_manifest_runs_only_the_modules_it_names(tmp_path, capsys):
    """A stray .py beside the plugin (a scratch script, a test) never runs; the digest covers
    only the manifest and what it names, so the stray file does not change the run's record."""
    marker = tmp_path / "MARKER"
    folder = _plant(tmp_path / "mixed", marker)                 # evil.py: not in the manifest
    _task_plugin(folder, "sec_manifest_task")
    _manifest(folder, modules=["sec_manifest_task"])
    rec = plugins.load_folder(folder)
    assert not marker.exists(), "a module the manifest does not name ran"
    from gpmotion.task import task_names
    assert "sec_manifest_task" in task_names()
    assert sorted(p.name for p in plugins.plugin_files(folder)) == [plugins.MANIFEST,
                                                                    "sec_manifest_task.py"]
    (folder / "evil.py").write_text("raise SystemExit('changed')\n")
    assert plugins.folder_digest(folder) == rec["digest"]


@pytest.mark.parametrize("text, message", [
    ('modules = ["../evil"]\n', "not a plain file name"),
    ('modules = ["missing"]\n', "not in"),
    ('modules = "evil"\n', "must be a list"),
    ('module = ["evil"]\n', "unknown key"),
    ('modules = [\n', "not valid TOML"),
    ('modules = []\n', "names no modules"),
])
def test_a_bad_manifest_is_one_line_and_runs_nothing(tmp_path, capsys, text, message):
    marker = tmp_path / "MARKER"
    folder = _plant(tmp_path / "bad", marker)
    (folder / plugins.MANIFEST).write_text(text)
    with pytest.raises(plugins.PluginError, match=message):
        plugins.load_folder(folder)
    capsys.readouterr()
    assert main(["list", "tasks", "--plugins", str(folder)]) == 2
    assert message.split()[0] in _one_line_error(capsys)
    assert not marker.exists()


def test_a_folder_without_a_manifest_still_loads_with_a_warning(tmp_path):
    folder = _task_plugin(tmp_path / "legacy", "sec_legacy_task")
    (folder / plugins.MANIFEST).unlink()
    with pytest.warns(FutureWarning, match=r"no gpmotion-plugin.toml.*modules = \['sec_legacy_task'\]"):
        plugins.load_folder(folder)
    from gpmotion.task import task_names
    assert "sec_legacy_task" in task_names()


def test_a_manifest_names_figures_and_a_clash_names_both(tmp_path):
    folder = tmp_path / "figs2"
    folder.mkdir()
    (folder / "sec_soft_lamp.toml").write_text('extends = "lamp"\nname = "sec_soft_lamp"\n')
    plugins.load_folder(_manifest(folder, figures=["sec_soft_lamp"]))
    from gpmotion import figure_names, load_figure
    assert "sec_soft_lamp" in figure_names() and load_figure("sec_soft_lamp").name == "sec_soft_lamp"
    clash = tmp_path / "clash"
    clash.mkdir()
    (clash / "lamp.toml").write_text('extends = "lamp"\nname = "lamp"\n')
    with pytest.raises(ValueError, match=r"figure 'lamp' is already registered.*lamp\.toml"):
        plugins.load_folder(_manifest(clash, figures=["lamp"]))


def test_entry_points_load_once_and_a_broken_one_is_skipped_with_a_warning(tmp_path, monkeypatch):
    calls = tmp_path / "calls"
    (tmp_path / "sec_ep_counter.py").write_text(
        f"from pathlib import Path\n"
        f"def setup():\n"
        f"    p = Path({str(calls)!r})\n"
        f"    p.write_text(p.read_text() + 'x' if p.exists() else 'x')\n")
    (tmp_path / "sec_ep_broken.py").write_text("raise ImportError('no numpy here')\n")
    info = tmp_path / "sec_ep_pkg2-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: sec-ep-pkg2\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[gpmotion.plugins]\nsec_counter = sec_ep_counter:setup\n"
                                           "sec_broken = sec_ep_broken\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.warns(RuntimeWarning, match="'sec_broken = sec_ep_broken' failed to load"):
        first = plugins.activate([])
    with pytest.warns(RuntimeWarning, match="sec_broken"):
        second = plugins.activate([])
    assert calls.read_text() == "x"                       # the callable ran once
    assert [r for r in first if r["name"] == "sec_counter"] == [r for r in second
                                                                 if r["name"] == "sec_counter"]
    assert not any(r["name"] == "sec_broken" for r in second)
