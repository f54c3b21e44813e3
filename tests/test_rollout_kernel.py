"""The rollout kernel is the real episode module with one line replaced, under a
key that hashes every gpmotion module it compiles; the harness reaches the
physics through named backends."""
from pathlib import Path

import numpy as np
import pytest

from gpmotion import cache
from gpmotion.controllers import schedule
from gpmotion.figures import load_figure
from gpmotion.sim import backend, episode, kernels
from gpmotion.sim.rollout import simulate


def test_generated_kernel_is_the_episode_module_but_for_the_controller_import():
    src = kernels.episode_source(schedule.KERNEL).splitlines()
    real = Path(episode.__file__).read_text().splitlines()
    changed = [line for line in real if line not in src]
    assert changed == [l for l in real if l.rstrip().endswith(kernels.MARK)]     # just that line
    assert f"_controller = import_file({str(Path(schedule.KERNEL).resolve())!r})" in src


def test_kernel_key_covers_helpers_imported_on_the_way(monkeypatch):
    """actuation.py is imported by planar.py and spatial3d.py, not by the episode
    module: editing it must still give another kernel (a stale one would run old physics)."""
    names = cache.package_modules(kernels.episode_source(schedule.KERNEL))
    for helper in ("gpmotion.sim.actuation", "gpmotion.sim.planar", "gpmotion.sim.spatial3d",
                   "gpmotion.sim.senses", "gpmotion.sim.backend_planar", "gpmotion.model"):
        assert helper in names
    before = kernels.kernel_key(schedule.KERNEL)
    actuation = names["gpmotion.sim.actuation"]
    real = cache.read_source
    monkeypatch.setattr(cache, "read_source",
                        lambda p: real(p) + (b"\n# edited\n" if Path(p) == actuation else b""))
    assert kernels.kernel_key(schedule.KERNEL) != before


def test_kernel_key_covers_the_controller_module(tmp_path):
    ctrl = tmp_path / "ctrl.py"
    ctrl.write_text(Path(schedule.KERNEL).read_text())
    before = kernels.kernel_key(str(ctrl))
    ctrl.write_text(ctrl.read_text() + "\n# edited\n")
    assert kernels.kernel_key(str(ctrl)) != before


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
