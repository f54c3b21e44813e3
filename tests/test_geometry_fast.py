"""The compiled planar poses and points a score reads are the numpy forms' values,
bit for bit (so every recorded cost stays what it was), on one thread and on two."""
import numpy as np
import pytest

from gpmotion.figures import load_figure
from gpmotion.sim import geometry, geometry_fast
from tests.figures_for_tests import free_star, pendulum

FIGURES = ["lamp", "starman", "beryl", pendulum(3, angle=-1.2), free_star()]


def _random_q(fig, rng, shape=(7, 41)):
    """Configurations from small to wild: negative slides (0 · d is −0 there), angles of many turns."""
    scale = rng.choice([0.1, 1.0, 30.0], size=shape + (fig.nq,))
    return rng.normal(size=shape + (fig.nq,)) * scale


@pytest.mark.parametrize("spec", FIGURES, ids=lambda s: s if isinstance(s, str) else s["name"])
def test_compiled_poses_and_points_are_the_numpy_ones_bit_for_bit(spec, monkeypatch):
    fig = load_figure(spec)
    m = fig.model
    q = _random_q(fig, np.random.default_rng(3))
    poses = geometry.link_poses(m, q)
    links = np.concatenate([fig.site_link, m.seg_link, m.cp_link, [-1]])
    local = np.concatenate([fig.site_pos, m.seg_a, m.cp_pos, [[0.3, -0.2]]])
    want = geometry.points_world(m, poses, links, local)
    for threads in ("1", "2"):
        monkeypatch.setattr(geometry_fast, "run_chunks",
                            _with_threads(geometry_fast.run_chunks, int(threads)))
        got_poses = geometry_fast.link_poses(m, q)
        assert got_poses.shape == poses.shape
        assert got_poses.tobytes() == poses.tobytes()          # −0.0 and +0.0 told apart
        got = geometry_fast.points_world(m, poses, links, local)
        assert got.shape == want.shape and got.tobytes() == want.tobytes()


def _with_threads(run_chunks, threads):
    def run(kernel, args, n, _=None):
        return run_chunks(kernel, args, n, threads)
    return run


def test_a_trajectory_reads_the_compiled_forms():
    """A lamp rollout's sites and base are the numpy forms' values on its recorded q."""
    import gpmotion
    fig = load_figure("lamp")
    traj = gpmotion.simulate(fig, 0.5, targets=fig.model.neutral + 0.3)
    poses = geometry.link_poses(fig.model, traj.q)
    assert traj.poses().tobytes() == poses.tobytes()
    k = fig.site_names.index("head_tip")
    want = geometry.points_world(fig.model, poses, fig.site_link[k:k + 1], fig.site_pos[k:k + 1])
    assert traj.site("head_tip").tobytes() == want[..., 0, :].tobytes()
