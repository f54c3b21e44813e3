"""BSR genomes: plain data, random initialization (Table 2), batch encoding.

Genomes are small dataclasses of numpy arrays, so they pickle, cross
processes and serialize to versioned JSON (``to_dict`` / ``genome_from_dict``)
with validation: untrusted files get one clear ``ValueError``.  Each genome
carries the ranges it was drawn in (joint limits, τ range, t_per) so mutation
needs nothing but the genome, an rng and (for the relevance heuristic) the
sense trajectory.

Table 2 initial distributions (Auslander et al.):
  τ      log-uniform in [2Δt, T/4]
  θ₀     uniform in [θ_min, θ_max] per joint
  μ      uniform in [−0.5, 1.5]
  2/λ    log-uniform in [0.4, 4]   ⇒ λ ∈ [0.5, 5], λ_min = 0.5
Validity ranges are Table 2's except μ, which may lie in [−2, 3]: the
relevance heuristic puts a box corner on a sense point in [0, 1] and the box
half-side is at most 2, so its centre can reach −2 or 3.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import math

import numpy as np

from gpmotion.controllers import ControllerBatch

LAMBDA_MIN = 2.0 / 4.0          # smallest allowable λ (largest side 4)
LAMBDA_MAX = 2.0 / 0.4          # largest λ (smallest side 0.4)
MU_INIT = (-0.5, 1.5)
DURATION_INIT = (0.5, 2.0)      # variable segments: relative durations, log-uniform
DURATION_BOUNDS = (0.1, 10.0)   # valid range of a relative duration
MU_BOUNDS = (-2.0, 3.0)
# The one bound on R, the rules per controller (the paper uses R = 10), for
# the command line, config files, study specs and controller files alike:
# memory is rules x senses per genome, and 10^7 rules would exhaust it mid-run.
MAX_RULES = 1000
MAX_WIDTH = 10_000              # cap on a row's width in untrusted files
SENSE_FORMAT = "bsr-sense-v1"
TIME_FORMAT = "bsr-time-v1"

_KERNELS = Path(__file__).resolve().parent
SENSE_KERNEL = str(_KERNELS / "sense_kernel.py")
TIME_KERNEL = str(_KERNELS / "time_kernel.py")


def tau_bounds(dt: float, T: float) -> tuple[float, float]:
    """Table 2's τ range [2Δt, T/4]; ValueError if empty."""
    lo, hi = 2.0 * float(dt), float(T) / 4.0
    if not (np.isfinite(lo) and np.isfinite(hi) and 0.0 < lo <= hi):
        raise ValueError(f"tau range [2*dt, T/4] = [{lo}, {hi}] is empty or "
                         f"invalid (dt={dt}, T={T})")
    return lo, hi


def exp(x):
    """e**x element by element with the C library's ``exp``.

    numpy's float64 ``exp`` and ``log`` take their own SIMD path on AVX-512
    machines and round some results differently from the C library's (which
    they call elsewhere), so a genome bred from a seed differed in its last
    bit between machines (a Mr. Star-Man golden run's τ, bred on
    an AVX-512 machine, came out one ulp away on an AVX2 one).  Variation
    goes through here so a seed gives the same genome everywhere."""
    a = np.asarray(x, dtype=np.float64)
    return np.array([math.exp(v) for v in a.ravel().tolist()]).reshape(a.shape)


def log_uniform(rng: np.random.Generator, lo: float, hi: float, size=None):
    """Log-uniform samples in [lo, hi] (clipped against rounding)."""
    x = exp(rng.uniform(math.log(lo), math.log(hi), size))
    return np.clip(x, lo, hi) if size is not None else float(np.clip(x, lo, hi))


def _array(name, value, ndim):
    try:
        a = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: not an array of numbers ({exc})") from None
    if a.ndim != ndim:
        raise ValueError(f"{name}: expected {ndim}-D array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains non-finite values")
    if a.size > MAX_RULES * MAX_WIDTH:
        raise ValueError(f"{name}: too large ({a.size} values)")
    return a if a.ndim == 0 else np.ascontiguousarray(a)


def _in_range(name, a, lo, hi):
    if np.any(a < lo) or np.any(a > hi):
        raise ValueError(f"{name}: values outside [{lo}, {hi}] "
                         f"(min {a.min()}, max {a.max()})")


def _response_arrays(g) -> None:
    """Make a genome's response part (θ₀, τ) and its ranges float arrays, checked."""
    g.theta0 = _array("theta0", g.theta0, 2)
    g.tau = _array("tau", g.tau, 1)
    g.limits = _array("limits", g.limits, 2)
    g.tau_range = _array("tau_range", g.tau_range, 1)
    _check_response(g.theta0, g.tau, g.limits, g.tau_range)


def _check_response(theta0, tau, limits, tau_range):
    """Shared checks of the response part (θ₀, τ) and its ranges."""
    n_rules, n_act = theta0.shape
    if not 1 <= n_rules <= MAX_RULES:
        raise ValueError(f"n_rules must be in [1, {MAX_RULES}], got {n_rules}")
    if n_act < 1:
        raise ValueError("theta0: needs at least one joint column")
    if tau.shape != (n_rules,):
        raise ValueError(f"tau: expected shape ({n_rules},), got {tau.shape}")
    if limits.shape != (n_act, 2):
        raise ValueError(f"limits: expected shape ({n_act}, 2), got {limits.shape}")
    if np.any(limits[:, 0] > limits[:, 1]):
        raise ValueError("limits: a lower joint limit exceeds its upper limit")
    if tau_range.shape != (2,) or not 0.0 < tau_range[0] <= tau_range[1]:
        raise ValueError(f"tau_range: expected [lo, hi] with 0 < lo <= hi, "
                         f"got {tau_range.tolist()}")
    bad = (theta0 < limits[:, 0]) | (theta0 > limits[:, 1])
    if np.any(bad):
        r, j = np.argwhere(bad)[0]
        raise ValueError(f"theta0[{r}, {j}] = {theta0[r, j]} outside joint "
                         f"limits {limits[j].tolist()}")
    _in_range("tau", tau, tau_range[0], tau_range[1])


def _expect_dict(d, fmt, keys):
    if not isinstance(d, dict):
        raise ValueError(f"genome must be a JSON object, got {type(d).__name__}")
    if d.get("format") != fmt:
        raise ValueError(f"genome format must be {fmt!r}, got {d.get('format')!r}")
    missing = [k for k in keys if k not in d]
    if missing:
        raise ValueError(f"genome ({fmt}) is missing field(s): {', '.join(missing)}")


def _trusted_copy(genome):
    """A deep copy without re-validation: the genome was validated when built,
    and mutation keeps every value in range (the serial search copies one
    genome per candidate, so validation would cost more than it checks)."""
    g = object.__new__(type(genome))
    g.__dict__.update({k: v.copy() if isinstance(v, np.ndarray) else v
                       for k, v in genome.__dict__.items()})
    return g


@dataclass(eq=False)
class SenseGenome:
    """Sense-based controller: rule j = (μ[j], λ[j]) → (θ₀[j], τ[j])."""
    mu: np.ndarray          # float64[R, V]  hyperrectangle centres
    lam: np.ndarray         # float64[R, V]  λ = 2 / side length
    theta0: np.ndarray      # float64[R, n_act] target poses
    tau: np.ndarray         # float64[R]     one time constant per rule
    limits: np.ndarray      # float64[n_act, 2] joint limits θ₀ is drawn in
    tau_range: np.ndarray   # float64[2]     [2Δt, T/4]

    kind = "sense"

    def __post_init__(self):
        self.mu = _array("mu", self.mu, 2)
        self.lam = _array("lam", self.lam, 2)
        _response_arrays(self)
        shape = (self.theta0.shape[0], self.mu.shape[1])
        if self.mu.shape != shape or self.lam.shape != shape or shape[1] < 1:
            raise ValueError(f"mu and lam must both have shape (n_rules, V) = "
                             f"{shape} with V >= 1, got {self.mu.shape} and "
                             f"{self.lam.shape}")
        _in_range("mu", self.mu, *MU_BOUNDS)
        _in_range("lam", self.lam, LAMBDA_MIN, LAMBDA_MAX)

    n_rules = property(lambda self: self.theta0.shape[0])
    n_senses = property(lambda self: self.mu.shape[1])
    n_act = property(lambda self: self.theta0.shape[1])

    @property
    def n_parameters(self) -> int:
        """(2V + n_act + 1)R; with V = 2N+2, n_act = N−1 this is (5N+4)R."""
        return self.mu.size + self.lam.size + self.theta0.size + self.tau.size

    def weights(self) -> np.ndarray:
        """W_j = Σ_k log(λ_jk / λ_min): specific (small) boxes score higher."""
        return np.log(self.lam / LAMBDA_MIN).sum(axis=1)

    def copy(self) -> "SenseGenome":
        return _trusted_copy(self)

    def to_dict(self) -> dict:
        return {"format": SENSE_FORMAT, "mu": self.mu.tolist(),
                "lam": self.lam.tolist(), "theta0": self.theta0.tolist(),
                "tau": self.tau.tolist(), "limits": self.limits.tolist(),
                "tau_range": self.tau_range.tolist()}

    @classmethod
    def from_dict(cls, d: dict) -> "SenseGenome":
        keys = ("mu", "lam", "theta0", "tau", "limits", "tau_range")
        _expect_dict(d, SENSE_FORMAT, keys)
        return cls(*(d[k] for k in keys))


@dataclass(eq=False)
class TimeGenome:
    """Time-based controller: segment r of period t_per → (θ₀[r], τ[r]).

    ``durations`` None: R equal segments (the default).  Otherwise float[R]
    relative durations d_r: segment r lasts d_r / Σd of t_per, so the
    controller has the paper's R − 1 free dividers per period (§4.1), held
    as one duration per rule so that creep and reinitialization of a rule
    move its segment's length too (footnote 6: N + 1 parameters per rule,
    θ₀ for N − 1 joints, τ and the duration).
    """
    theta0: np.ndarray      # float64[R, n_act]
    tau: np.ndarray         # float64[R]
    t_per: float            # period, seconds (set by the user, not evolved)
    limits: np.ndarray      # float64[n_act, 2]
    tau_range: np.ndarray   # float64[2]
    durations: np.ndarray | None = None   # float64[R] relative, or None: equal

    kind = "time"

    def __post_init__(self):
        _response_arrays(self)
        t_per = _array("t_per", self.t_per, 0)
        if not t_per > 0.0:
            raise ValueError(f"t_per must be > 0, got {float(t_per)}")
        self.t_per = float(t_per)
        if self.durations is not None:
            self.durations = _array("durations", self.durations, 1)
            if self.durations.shape != self.tau.shape:
                raise ValueError(f"durations: expected shape {self.tau.shape}, "
                                 f"got {self.durations.shape}")
            _in_range("durations", self.durations, *DURATION_BOUNDS)

    n_rules = property(lambda self: self.theta0.shape[0])
    n_act = property(lambda self: self.theta0.shape[1])

    @property
    def n_parameters(self) -> int:
        """(n_act + 1)R: θ₀ per joint and one τ per segment (+ R − 1 dividers
        with variable segments)."""
        extra = 0 if self.durations is None else self.n_rules - 1
        return self.theta0.size + self.tau.size + extra

    def boundaries(self) -> np.ndarray:
        """The R − 1 inner segment ends as fractions of t_per (empty: equal)."""
        if self.durations is None:
            return np.zeros(0)
        c = np.cumsum(self.durations)
        return c[:-1] / c[-1]

    def copy(self) -> "TimeGenome":
        return _trusted_copy(self)

    def to_dict(self) -> dict:
        d = {"format": TIME_FORMAT, "theta0": self.theta0.tolist(),
             "tau": self.tau.tolist(), "t_per": self.t_per,
             "limits": self.limits.tolist(), "tau_range": self.tau_range.tolist()}
        if self.durations is not None:
            d["durations"] = self.durations.tolist()
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "TimeGenome":
        keys = ("theta0", "tau", "t_per", "limits", "tau_range")
        _expect_dict(d, TIME_FORMAT, keys)
        return cls(*(d[k] for k in keys), durations=d.get("durations"))


def genome_from_dict(d: dict) -> SenseGenome | TimeGenome:
    """Parse either genome kind by its ``format`` field."""
    fmt = d.get("format") if isinstance(d, dict) else None
    if fmt == SENSE_FORMAT:
        return SenseGenome.from_dict(d)
    if fmt == TIME_FORMAT:
        return TimeGenome.from_dict(d)
    raise ValueError(f"unknown genome format {fmt!r}; expected "
                     f"{SENSE_FORMAT!r} or {TIME_FORMAT!r}")


def table1_sense_indices(sense_names) -> np.ndarray:
    """Indices of Table 1's senses in a figure's sense vector.

    Joint angles (``angle_*``), contact forces (``force_*``), ``com_z`` and
    ``com_vz``: V = n_act + n_contacts + 2, which is the paper's 2N+2 for an
    N-rod chain with N−1 joints and N+1 rod endpoints as contact points.
    """
    names = list(sense_names)
    idx = [i for i, n in enumerate(names) if n.startswith("angle_")]
    idx += [i for i, n in enumerate(names) if n.startswith("force_")]
    for n in ("com_z", "com_vz"):
        if n not in names:
            raise ValueError(f"sense {n!r} missing; Table 1 needs it")
        idx.append(names.index(n))
    return np.array(idx, dtype=np.int64)


def random_theta0(rng, limits, n_rules):
    limits = np.asarray(limits, dtype=np.float64)
    return rng.uniform(limits[:, 0], limits[:, 1], (n_rules, limits.shape[0]))


def random_stimulus(rng, n_rules, n_senses):
    """Table 2 μ and λ for n_rules fresh rules."""
    mu = rng.uniform(MU_INIT[0], MU_INIT[1], (n_rules, n_senses))
    lam = np.clip(2.0 / log_uniform(rng, 0.4, 4.0, (n_rules, n_senses)),
                  LAMBDA_MIN, LAMBDA_MAX)
    return mu, lam


def random_sense_genome(rng: np.random.Generator, n_rules: int, n_senses: int,
                        limits, dt: float, T: float) -> SenseGenome:
    """A random sense-based controller drawn from Table 2."""
    lo, hi = tau_bounds(dt, T)
    limits = np.asarray(limits, dtype=np.float64)
    mu, lam = random_stimulus(rng, n_rules, n_senses)
    theta0 = random_theta0(rng, limits, n_rules)
    tau = log_uniform(rng, lo, hi, n_rules)
    return SenseGenome(mu, lam, theta0, tau, limits, np.array([lo, hi]))


def random_time_genome(rng: np.random.Generator, n_rules: int, limits,
                       dt: float, T: float, t_per: float,
                       segments: str = "equal") -> TimeGenome:
    """A random time-based controller (responses from Table 2).

    ``segments="variable"``: relative durations log-uniform in DURATION_INIT
    (the paper gives no distribution; segments from 1/4 to 4 times another),
    drawn after the responses so equal-segment genomes are unchanged.
    """
    if segments not in ("equal", "variable"):
        raise ValueError(f"segments must be 'equal' or 'variable', got {segments!r}")
    lo, hi = tau_bounds(dt, T)
    limits = np.asarray(limits, dtype=np.float64)
    theta0 = random_theta0(rng, limits, n_rules)
    tau = log_uniform(rng, lo, hi, n_rules)
    durations = log_uniform(rng, *DURATION_INIT, n_rules) if segments == "variable" else None
    return TimeGenome(theta0, tau, t_per, limits, np.array([lo, hi]), durations)


def encode_batch(genomes, sense_indices=None, n_act: int | None = None,
                 actuators=None) -> ControllerBatch:
    """Program arrays for one batched rollout (layouts: the kernel modules).

    ``sense_indices`` (int[V]) says which entries of ``senses_norm`` a
    sense-based genome's V stimulus columns read; it is ignored for
    time-based genomes.  ``n_act`` (the number of driven actuators) must
    equal every genome's θ₀ width.  ``actuators`` (int[n_act], default
    0..n_act−1) are the figure actuators the θ₀ columns drive (a task's
    ``controlled_actuators``); the others hold their neutral pose, as GP's.
    """
    genomes = list(genomes)
    if not genomes:
        raise ValueError("encode_batch: no genomes")
    kinds = {g.kind for g in genomes}
    if len(kinds) != 1:
        raise ValueError(f"encode_batch: mixed genome kinds {sorted(kinds)}")
    widths = {g.n_act for g in genomes}
    if len(widths) != 1 or (n_act is not None and widths != {n_act}):
        raise ValueError(f"encode_batch: genome joint counts {sorted(widths)} "
                         f"do not match n_act={n_act}")
    n_act = widths.pop()
    amap = np.arange(n_act) if actuators is None else np.asarray(actuators, dtype=np.int64).ravel()
    if amap.size != n_act or np.any(amap < 0) or np.unique(amap).size != n_act:
        raise ValueError(f"encode_batch: actuators must be {n_act} distinct "
                         f"non-negative indices, got {amap.tolist()}")
    rows_i, rows_f = [], []
    if kinds == {"sense"}:
        from gpmotion.bsr.sense_kernel import CSTATE_SIZE
        if sense_indices is None:
            raise ValueError("encode_batch: sense-based genomes need sense_indices")
        idx = np.asarray(sense_indices, dtype=np.int64).ravel()
        if np.any(idx < 0):
            raise ValueError("encode_batch: sense-based genomes need "
                             "non-negative sense_indices")
        for g in genomes:
            if g.n_senses != idx.size:
                raise ValueError(f"encode_batch: genome reads {g.n_senses} "
                                 f"senses but {idx.size} sense_indices given")
            rows_i.append(np.concatenate([[g.n_rules, idx.size, n_act], idx, amap]))
            rows_f.append(np.hstack([g.weights()[:, None], g.tau[:, None],
                                     g.mu, g.lam, g.theta0]).ravel())
        module, cstate_size = SENSE_KERNEL, CSTATE_SIZE
    else:
        from gpmotion.bsr.time_kernel import CSTATE_SIZE
        for g in genomes:
            rows_i.append(np.concatenate([[g.n_rules, n_act, g.durations is not None], amap]))
            rows_f.append(np.concatenate(
                [[g.t_per], np.hstack([g.tau[:, None], g.theta0]).ravel(), g.boundaries()]))
        module, cstate_size = TIME_KERNEL, CSTATE_SIZE
    ci = np.zeros((len(genomes), max(r.size for r in rows_i)), dtype=np.int64)
    cf = np.zeros((len(genomes), max(r.size for r in rows_f)), dtype=np.float64)
    for e, (ri, rf) in enumerate(zip(rows_i, rows_f)):
        ci[e, :ri.size] = ri
        cf[e, :rf.size] = rf
    return ControllerBatch(module=module, ci=ci, cf=cf, cstate_size=cstate_size)
