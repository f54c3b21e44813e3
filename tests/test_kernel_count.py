"""benchmarks/kernel_count.py: the generated kernels a command loads, in every process it starts."""
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TOOL = ROOT / "benchmarks" / "kernel_count.py"
sys.path.insert(0, str(TOOL.parent))
import kernel_count  # noqa: E402


def _count(code: str, tmp_path) -> str:
    log = tmp_path / "kernels.log"
    out = subprocess.run([sys.executable, str(TOOL), "--log", str(log), "--",
                          sys.executable, "-c", textwrap.dedent(code)],
                         capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_two_function_sets_of_installed_primitives_load_one_interpreter(tmp_path):
    out = _count("""
        from gpmotion.gp.interpreter import load_interpreter
        from gpmotion.gp.pset import build_pset
        load_interpreter(build_pset(["x"], ["add", "sub"]))
        load_interpreter(build_pset(["x"]))
        load_interpreter(build_pset(["x"], ["ifpos", "mul"]))
        """, tmp_path)
    assert out.splitlines()[0] == "generated modules loaded: 1 gp", out
    assert "ifpos" in out.splitlines()[1]
    assert out.splitlines()[2].startswith("added to the cache folder: ")


def test_on_an_empty_cache_what_a_command_compiles_is_listed(tmp_path, monkeypatch):
    monkeypatch.setenv("GPMOTION_CACHE", str(tmp_path / "cache"))
    out = _count("""
        from gpmotion.gp.interpreter import load_interpreter
        from gpmotion.gp.pset import build_pset
        load_interpreter(build_pset(["x"], ["add"]))
        """, tmp_path)
    assert out.splitlines()[2:] == ["added to the cache folder: 1 gp",
                                    "  gp       abs, add, cos, div, iflte, mul, sin, sub, ifpos"], out


def test_a_child_process_is_counted_and_the_exit_status_kept(tmp_path):
    out = subprocess.run([sys.executable, str(TOOL), "--", sys.executable, "-c", textwrap.dedent("""
        import subprocess, sys
        subprocess.run([sys.executable, "-c", "from gpmotion.gp.interpreter import load_interpreter;"
                        "from gpmotion.gp.pset import build_pset;"
                        "load_interpreter(build_pset(['x']))"], check=True)
        sys.exit(3)
        """)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert out.returncode == 3
    assert out.stdout.splitlines()[0] == "generated modules loaded: 1 gp", out.stdout


def test_a_rollout_kernel_is_named_by_its_controller_and_backend(tmp_path):
    from gpmotion.controllers import schedule
    from gpmotion.sim.kernels import episode_source
    package = tmp_path / "rollout_package.py"
    package.write_text(episode_source(schedule.KERNEL, "planar"))
    assert kernel_count.describe(package) == ("rollout", "schedule_kernel.py on backend_planar")
    own = tmp_path / "my_controller.py"
    own.write_text(Path(schedule.KERNEL).read_text())
    outside = tmp_path / "rollout_outside.py"
    outside.write_text(episode_source(str(own), "3d"))
    assert kernel_count.describe(outside) == ("rollout", "my_controller.py on backend_3d")
