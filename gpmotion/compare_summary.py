"""A comparison's summary: per family, cost quartiles, success rate and the
learning-curve bands.  Plain data over the per-run records, so the report can
read a comparison without importing the code that runs one."""
from __future__ import annotations

import warnings

import numpy as np


def _nan(x):
    return float("nan") if x is None else float(x)


def summarize(runs: list[dict]) -> list[dict]:
    rows = []
    for fam in dict.fromkeys(r["family"] for r in runs):
        rs = [r for r in runs if r["family"] == fam]
        c = np.array([r["final_cost"] for r in rs])
        firsts = [r["first_success"] for r in rs if r["first_success"] is not None]
        rows.append({"controller": fam, "runs": len(rs),
                     "cost_q25": float(np.percentile(c, 25)), "cost_median": float(np.median(c)),
                     "cost_q75": float(np.percentile(c, 75)),
                     "success_rate": float(np.mean([r["success"] for r in rs])),
                     "runs_with_solver": len(firsts),
                     "evals_to_success_median": float(np.median(firsts)) if firsts else None,
                     "wall_s_median": float(np.median([r["wall_s"] for r in rs]))})
    return rows


def _bands(runs, budget, key="curve"):
    """Per family: (grid, q25, median, q75) of the runs' step curves ``key``."""
    grid = np.linspace(0, budget, 60)[1:]
    series = {}
    for fam in dict.fromkeys(r["family"] for r in runs):
        ys = []
        for r in (r for r in runs if r["family"] == fam):
            e = np.array([p[0] for p in r[key]], dtype=np.float64)
            b = np.array([_nan(p[1]) for p in r[key]])
            idx = np.searchsorted(e, grid, side="right") - 1
            ys.append(np.where(idx >= 0, b[np.clip(idx, 0, None)], np.nan))
        y = np.array(ys)
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)   # before a run's first point
            series[fam] = (grid, *np.nanpercentile(y, [25, 50, 75], axis=0))
    return series
