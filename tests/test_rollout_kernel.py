"""The rollout kernel is the real episode module with two import lines replaced
(backend and controller), under a key that hashes every gpmotion module it
compiles; the harness reaches the physics through named backends."""
import sys
from pathlib import Path

import numpy as np
import pytest

from gpmotion import cache
from gpmotion.controllers import schedule
from gpmotion.figures import load_figure
from gpmotion.sim import backend, episode, kernels
from gpmotion.sim import threads as threads_module
from gpmotion.sim.rollout import simulate


@pytest.mark.parametrize("name", sorted(backend.BACKENDS))
def test_generated_kernel_is_the_episode_module_but_for_two_imports(name):
    src = kernels.episode_source(schedule.KERNEL, name).splitlines()
    real = Path(episode.__file__).read_text().splitlines()
    changed = [line for line in real if line not in src]
    marked = [l for l in real if l.rstrip().endswith((kernels.MARK, kernels.BACKEND_MARK))]
    assert changed == marked and len(marked) == 2                               # just those lines
    assert "import gpmotion.controllers.schedule_kernel as _controller" in src
    assert any(l.startswith(f"from {backend.BACKENDS[name].__name__} import ") for l in src)


def test_a_package_controllers_kernel_names_no_folder_of_the_install(tmp_path):
    """The same source wherever gpmotion lives: a second checkout finds the kernels
    the first compiled; a controller module outside the package is named by path."""
    root = str(Path(kernels.__file__).resolve().parents[2])
    assert root not in kernels.episode_source(schedule.KERNEL, "planar")
    ctrl = tmp_path / "my_controller.py"
    ctrl.write_text(Path(schedule.KERNEL).read_text())
    assert f"import_file({str(ctrl.resolve())!r})" in kernels.episode_source(str(ctrl), "planar")


def test_kernels_differ_per_backend():
    keys = {kernels.kernel_key(schedule.KERNEL, name) for name in backend.BACKENDS}
    assert len(keys) == len(backend.BACKENDS)


def test_kernel_key_covers_helpers_imported_on_the_way(monkeypatch):
    """actuation.py is imported by planar.py and spatial3d.py, not by the episode
    module: editing it must still give another kernel (a stale one would run old physics)."""
    names = cache.package_modules(kernels.episode_source(schedule.KERNEL, "planar"))
    for helper in ("gpmotion.sim.actuation", "gpmotion.sim.planar", "gpmotion.sim.spatial3d",
                   "gpmotion.sim.senses", "gpmotion.sim.backend_planar", "gpmotion.model"):
        assert helper in names
    before = kernels.kernel_key(schedule.KERNEL, "planar")
    actuation = names["gpmotion.sim.actuation"]
    real = cache.read_source
    monkeypatch.setattr(cache, "read_source",
                        lambda p: real(p) + (b"\n# edited\n" if Path(p) == actuation else b""))
    assert kernels.kernel_key(schedule.KERNEL, "planar") != before


def test_kernel_key_covers_the_controller_module(tmp_path):
    ctrl = tmp_path / "ctrl.py"
    ctrl.write_text(Path(schedule.KERNEL).read_text())
    before = kernels.kernel_key(str(ctrl), "planar")
    ctrl.write_text(ctrl.read_text() + "\n# edited\n")
    assert kernels.kernel_key(str(ctrl), "planar") != before


def test_package_modules_resolves_relative_imports_and_skips_attributes():
    src = "from .actuation import servo\nfrom gpmotion.sim import planar\nimport numpy\n"
    found = cache.package_modules(src, "gpmotion.sim")
    assert {"gpmotion.sim.actuation", "gpmotion.sim.planar"} <= set(found)
    assert "gpmotion.sim.actuation.servo" not in found and "numpy" not in found
    assert "gpmotion" not in found          # passed through, nothing taken from it


@pytest.mark.parametrize("name, dims", [("lamp", 2), ("herman", 3)])
def test_backend_by_name(name, dims):
    fig = load_figure(name)
    b = backend.backend_of(fig)
    assert b is backend.BACKENDS[fig.model.BACKEND] and fig.model.DIMENSIONS == dims == fig.dimensions
    assert backend.backend_of(fig.model) is b


def test_trajectory_geometry_comes_from_the_backend():
    tr = simulate("lamp", 0.05)
    m = tr.figure.model
    assert tr.backend is backend.backend_planar and not tr.is3d
    np.testing.assert_array_equal(tr.base(), tr.poses()[..., m.base_link, :])
    assert tr.segments().shape == tr.q.shape[:2] + (len(m.seg_link), 2, 2)


@pytest.mark.parametrize("name", ["lamp", "herman"])
def test_borrowed_views_leave_no_reference_behind(name):
    """The episode loop reads the model, scene and workspace through uncounted views
    (gpmotion.sim.borrow): a rollout must neither leak nor drop a reference to the
    model's arrays (a dropped one would free them under the caller)."""
    fig = load_figure(name)
    simulate(fig, 0.01)                                   # compile and warm up
    arrays = [a for a in fig.model if isinstance(a, np.ndarray)]
    before = [sys.getrefcount(a) for a in arrays]
    for _ in range(3):
        simulate(fig, 0.01)
    assert [sys.getrefcount(a) for a in arrays] == before


def test_borrowed_is_the_same_arrays():
    from numba import njit
    from gpmotion.sim.borrow import borrowed

    @njit
    def write_through(w):
        b = borrowed(w)
        b[0][0] = 7.0
        b[1][1] = 3
        return b[0].sum() + b[2]

    w = (np.zeros(3), np.zeros(2, dtype=np.int64), 1.5)
    assert write_through(w) == 8.5
    assert w[0][0] == 7.0 and w[1][1] == 3


def test_every_way_of_giving_a_start_state_uses_one_kernel_signature():
    """A second numba signature is a second compile of the whole episode (a minute
    for herman): a start row, a batch, a Fortran-ordered batch and none all give
    C-ordered copies."""
    from gpmotion.model import make_scene
    from gpmotion.sim.rollout import rollout
    fig = load_figure("lamp")
    ctrl = schedule.sines(np.tile(fig.model.neutral, (3, 1)), 0.0, 1.0, 0.0)     # 3 episodes
    q = np.tile(fig.q_default, (3, 1))
    for q0 in (None, fig.q_default, q, np.asfortranarray(q)):
        rollout(fig, make_scene(), ctrl, n_steps=5, q0=q0, qd0=None if q0 is None else np.zeros_like(q0))
    kernel = kernels.kernel_for(schedule.KERNEL, "planar")
    assert len(kernel.rollout_batch.signatures) == 1


def _shipped_kernel_modules():
    from gpmotion.bsr import genome, senses3d
    from gpmotion.families import make_family
    from gpmotion.task import get_task
    fam = make_family("gp", get_task("lamp_hop"))
    rng = np.random.default_rng(0)
    gp_module = fam.encode([fam.random(rng) for _ in range(2)]).module
    return {"schedule": schedule.KERNEL, "bsr-time": genome.TIME_KERNEL,
            "bsr-sense": genome.SENSE_KERNEL, "bsr-sense 3-D": senses3d.KERNEL, "gp": gp_module}


def test_kernel_modules_set_every_option_numba_would_inherit():
    """An unset option is inherited from the first kernel that compiles the
    function, and the disk cache keeps that version: a GP module compiled first
    from the 3-D loop (which contracts multiply-adds) gave other last bits than
    one compiled first from the planar loop.  Every njit of a kernel module sets
    fastmath, error_model and boundscheck (directly or through its JIT dict)."""
    import ast
    from gpmotion import controllers
    for name, path in _shipped_kernel_modules().items():
        module = cache.import_file(path)
        for node in ast.walk(ast.parse(Path(path).read_text())):
            if not isinstance(node, ast.FunctionDef):
                continue
            for dec in node.decorator_list:
                if isinstance(dec, ast.Call) and getattr(dec.func, "id", "") == "njit":
                    keys = {k.arg for k in dec.keywords if k.arg}
                    for k in dec.keywords:
                        if k.arg is None:                      # **FLAGS
                            keys |= set(getattr(module, k.value.id))
                    assert {"fastmath", "error_model", "boundscheck"} <= keys, (name, node.name)
    assert controllers.KERNEL_JIT["fastmath"] is False


_ORDER_SCRIPT = """
import sys
from gpmotion.task import get_task
from gpmotion.families import make_family
from gpmotion.replay import replay_genome
import numpy as np
out = []
for name in sys.argv[1:]:
    task = get_task(name)
    fam = make_family("gp", task)
    rng = np.random.default_rng(5)
    genomes = [fam.random(rng) for _ in range(3)]
    out.append([float(replay_genome(task, fam, fam.default_actuation, g)[1][0]).hex() for g in genomes])
print(out[-1])
"""


@pytest.mark.slow
def test_a_gp_rollout_does_not_depend_on_which_kernel_compiled_its_module_first(tmp_path):
    """The same GP controllers on Herman (touch_object: rate targets, whose law
    integrates with a multiply-add), compiled in a fresh cache after the planar
    lamp's kernel (which shares the primitive set's module) and alone: the same
    bits (before every kernel module set its numba options, 1e-15 rad apart at
    once, and an evolved run went another way)."""
    import subprocess
    runs = []
    for i, order in enumerate((["lamp_hop", "herman_touch_object"], ["herman_touch_object"])):
        env = dict(__import__("os").environ, GPMOTION_CACHE=str(tmp_path / f"cache{i}"))
        runs.append(subprocess.run([sys.executable, "-c", _ORDER_SCRIPT, *order], env=env,
                                   check=True, capture_output=True, text=True).stdout)
    assert runs[0] == runs[1]


class _Spy:
    """A rollout kernel that records which thread ran which chunk of episodes."""

    def __init__(self, kernel, fail_at=None):
        self.kernel, self.fail_at, self.chunks = kernel, fail_at, []

    def rollout_batch(self, *args):
        import threading
        lo, hi = args[-2:]
        if self.fail_at is not None and lo <= self.fail_at < hi:
            raise RuntimeError(f"chunk {lo}-{hi}")
        self.chunks.append((lo, hi, threading.get_ident()))
        self.kernel.rollout_batch(*args)


def _varied_lamp_batch(n):
    fig = load_figure("lamp")
    rng = np.random.default_rng(3)
    amp = rng.uniform(0.0, 1.5, (n, fig.n_act))          # some fall, some hop, some hold
    return fig, schedule.sines(np.tile(fig.model.neutral, (n, 1)), amp, rng.uniform(2, 12, (n, fig.n_act)), 0.0)


def test_threads_share_a_batch_out_and_give_one_threads_results(monkeypatch):
    """Chunks cover every episode once, more than one thread runs them, and each
    episode's channels are those of the same batch on one thread, bit for bit."""
    from gpmotion.model import make_scene
    from gpmotion.sim import rollout as rollout_module
    fig, ctrl = _varied_lamp_batch(13)
    serial = rollout_module.rollout(fig, make_scene(), ctrl, n_steps=2000, threads=1)
    monkeypatch.setattr(threads_module, "default_threads", lambda: 3)   # not capped by this machine
    real = rollout_module.kernel_for
    spies = []
    monkeypatch.setattr(rollout_module, "kernel_for",
                        lambda *a: spies.append(_Spy(real(*a))) or spies[-1])
    threaded = rollout_module.rollout(fig, make_scene(), ctrl, n_steps=2000, threads=3)
    chunks = sorted(c for c in spies[0].chunks if c[0] < c[1])
    assert [c[:2] for c in chunks] == list(zip(range(0, 13, 2), [*range(2, 13, 2), 13]))
    assert len({c[2] for c in chunks}) > 1
    for name in ("q", "qd", "com", "contact_force", "pole_hit", "impact", "energy", "targets",
                 "diverged", "diverged_step", "contact_end"):
        assert np.array_equal(getattr(serial, name), getattr(threaded, name)), name


def test_a_chunks_error_reaches_the_caller(monkeypatch):
    from gpmotion.model import make_scene
    from gpmotion.sim import rollout as rollout_module
    fig, ctrl = _varied_lamp_batch(6)
    monkeypatch.setattr(threads_module, "default_threads", lambda: 2)
    real = rollout_module.kernel_for
    monkeypatch.setattr(rollout_module, "kernel_for", lambda *a: _Spy(real(*a), fail_at=4))
    with pytest.raises(RuntimeError, match="chunk 4-5"):
        rollout_module.rollout(fig, make_scene(), ctrl, n_steps=50, threads=2)


def test_one_process_at_a_time_compiles_a_kernel(tmp_path):
    """The compile lock excludes other processes: another process that takes it
    after us gets it only once we let go (then it loads what we cached)."""
    import subprocess
    import textwrap
    from gpmotion.compile_events import compile_lock
    module, log = tmp_path / "rollout_x.py", tmp_path / "log"
    child = textwrap.dedent(f"""
        from gpmotion.compile_events import compile_lock
        with compile_lock({str(module)!r}):
            open({str(log)!r}, "a").write("child\\n")
    """)
    with compile_lock(module):
        proc = subprocess.Popen([sys.executable, "-c", child])
        try:
            proc.wait(timeout=3)
        except subprocess.TimeoutExpired:       # blocked on our lock, as it should be
            pass
        log.write_text("parent\n")              # only we hold it: the child has not written
    assert proc.wait(timeout=60) == 0
    assert log.read_text() == "parent\nchild\n"
    assert (tmp_path / "rollout_x.lock").exists()
