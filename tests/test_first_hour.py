"""What a new user meets first: the README's install commands, in order."""
import os
import shutil
import site
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
_NOT_SOURCES = shutil.ignore_patterns(".git", "runs", "build", "dist", "__pycache__", "*.egg-info",
                                      ".hypothesis", ".benchmarks", ".ruff_cache", ".venv",
                                      ".pytest_cache", "*.nbi", "*.nbc")


def _venv_with_this_pythons_packages(where: Path) -> Path:
    """A fresh venv whose dependencies are this interpreter's (no download):
    its site-packages are appended to the venv's path by a .pth file, after
    the venv's own, so what pip installs into the venv comes first."""
    subprocess.run([sys.executable, "-m", "venv", str(where)], check=True)
    py = where / ("Scripts" if os.name == "nt" else "bin") / "python"
    venv_site = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               check=True, capture_output=True, text=True).stdout.strip()
    outer = [p for p in site.getsitepackages() + [site.getusersitepackages()] if os.path.isdir(p)]
    Path(venv_site, "outer_packages.pth").write_text("\n".join(outer) + "\n")
    return py


def _in(folder: Path, env: dict, *cmd: str) -> subprocess.CompletedProcess:
    r = subprocess.run(cmd, cwd=folder, env=env, capture_output=True, text=True)
    assert r.returncode == 0, f"{' '.join(cmd)} (in {folder}) exit {r.returncode}:\n{r.stdout[-2000:]}\n{r.stderr[-3000:]}"
    return r


def test_the_readme_install_commands_in_order_leave_a_working_gpmotion(tmp_path):
    """`pip install .`, a run, then `pip install -e ".[test]"` (the README's two
    commands in that order) into one fresh venv: gpmotion still works from any
    folder.  numba's cache files written inside the installed package survived
    the uninstall as a namespace package that shadowed the editable install
    (`No module named 'gpmotion.sim.senses'`, `gpmotion` without `RunConfig`)."""
    clone = tmp_path / "clone"
    shutil.copytree(REPO, clone, ignore=_NOT_SOURCES)
    py = _venv_with_this_pythons_packages(tmp_path / "venv")
    gpmotion = str(py.parent / "gpmotion")
    # as a user's shell: none of this process's cache settings, the user's cache folder
    env = {k: v for k, v in os.environ.items()
           if k not in ("NUMBA_CACHE_DIR", "GPMOTION_NUMBA_CACHE_DIR", "PYTHONPATH")}
    pip = (str(py), "-m", "pip", "install", "-q", "--disable-pip-version-check")
    _in(clone, env, *pip, ".")
    _in(clone, env, gpmotion, "run", "lamp_hop", "--generations", "1", "--population", "4",
        "--no-artifacts", "--quiet")
    installed = Path(_in(tmp_path, env, str(py), "-c", "import gpmotion; print(gpmotion.__file__)")
                     .stdout.strip()).parent
    assert not list(installed.rglob("*.nb[ic]")), "numba cache files inside the installed package"
    _in(clone, env, *pip, "-e", ".[test]")
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    listed = _in(outside, env, gpmotion, "list").stdout
    assert "lamp_hop" in listed
    where = _in(outside, env, str(py), "-c",
                "import gpmotion; gpmotion.RunConfig; print(gpmotion.__file__)").stdout.strip()
    assert Path(where).resolve().parent == (clone / "gpmotion").resolve()


def test_numba_caches_in_the_user_cache_keyed_by_version_and_cpu(tmp_path, monkeypatch):
    import numba
    from gpmotion import cache
    from gpmotion.version import __version__
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)   # restored after
    monkeypatch.setenv("GPMOTION_CACHE", str(tmp_path / "c"))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    cache.configure_numba()
    here = tmp_path / "c" / __version__ / cache.cpu_key()
    assert os.environ["NUMBA_CACHE_DIR"] == numba.config.CACHE_DIR == str(here / "numba")
    assert cache.cache_dir() == here / "kernels"
    # a child process given this environment and another cache root follows its own
    monkeypatch.setenv("GPMOTION_CACHE", str(tmp_path / "d"))
    cache.configure_numba()
    assert os.environ["NUMBA_CACHE_DIR"].startswith(str(tmp_path / "d"))
    # the user's own NUMBA_CACHE_DIR is kept
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    cache.configure_numba()
    assert os.environ["NUMBA_CACHE_DIR"] == numba.config.CACHE_DIR == str(tmp_path / "mine")


def test_the_cpu_key_names_the_target_numba_compiles_for(monkeypatch):
    from gpmotion import cache
    host = cache.cpu_key()
    monkeypatch.setenv("NUMBA_CPU_NAME", "x86-64-v3")
    monkeypatch.setenv("NUMBA_CPU_FEATURES", "")
    cache._compile_target.cache_clear()
    cache.cpu_key.cache_clear()
    try:
        fixed = cache.cpu_key()
        assert fixed.startswith("x86-64-v3-") and fixed != host
    finally:
        monkeypatch.undo()
        cache._compile_target.cache_clear()
        cache.cpu_key.cache_clear()
    assert cache.cpu_key() == host


def _shown_numbers(line: str) -> tuple:
    import re
    m = re.search(r"best so far (\S+) \(median (\S+)\)  best final (\S+)", line)
    assert m, line
    return m.groups()


@pytest.mark.parametrize("task, extra", [("lamp_hop", ["--preset", "gritz-hahn"]),
                                         ("lamp_limbo", [])])
def test_the_progress_line_shows_the_numbers_of_the_log_row(task, extra, tmp_path, capsys):
    """best so far and the median beside it under the current weights, best final
    under the final weights: the same numbers as log.csv's row, also under the
    paper's preset and the limbo's curriculum (best final unknown until it ends)."""
    import csv
    from gpmotion.cli import main
    out = tmp_path / "r"
    assert main(["run", task, *extra, "--out", str(out), "--param", "seconds=0.3",
                 "--population", "8", "--generations", "3", "--no-artifacts"]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if ln.lstrip("\r").startswith("gen ")]
    with open(out / "log.csv", newline="") as f:
        row = list(csv.DictReader(f))[-1]
    want = (f"{float(row['best_so_far']):.4f}", f"{float(row['gen_median']):.4f}",
            "–" if row["best_final"] == "" else f"{float(row['best_final']):.4f}")
    assert _shown_numbers(lines[-1]) == want
