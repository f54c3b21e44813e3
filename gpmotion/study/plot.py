"""A study's figure: success rates with 95 % Wilson intervals (report seeds;
tune seeds: counts, no interval), and learning curves per configuration —
each run's best cost so far under the final weights against evaluations
(kept in the ledger from the run's log.csv), median and quartile band.
The rates are the table's (:func:`gpmotion.study.table.summarize`)."""
from __future__ import annotations

import warnings

import numpy as np

from .table import chosen, summarize


def _band(curves: list, grid: np.ndarray):
    ys = []
    for c in curves:
        if not c:
            continue
        e = np.array([p[0] for p in c], float)
        b = np.array([p[1] for p in c], float)
        idx = np.searchsorted(e, grid, side="right") - 1
        ys.append(np.where(idx >= 0, b[np.clip(idx, 0, None)], np.nan))
    if not ys:
        return None
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanpercentile(np.array(ys), [25, 50, 75], axis=0)


def plot(spec, rows: list[dict], path, seed_set: str = "report", judge: str | None = None):
    from matplotlib.figure import Figure

    from ..render import _save_png
    summary = summarize(spec, rows, seed_set, judge)
    items = [r for r in summary["rows"] if r["runs"]]
    if not items:
        raise ValueError(f"{spec.name}: no {seed_set}-seed rows to plot")
    fig = Figure(figsize=(11, 0.45 * len(items) + 2.2))
    ax, bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.3]})
    ys = np.arange(len(items))[::-1]
    for y, r in zip(ys, items):
        if r["success"] is None:
            continue
        p = r["success"] / r["tested"]
        if "interval95" in r:
            lo, hi = r["interval95"]
            ax.errorbar(p, y, xerr=[[p - lo], [hi - p]], fmt="o", color="C0", capsize=3)
        else:
            ax.plot(p, y, "o", color="0.5")
        ax.text(1.02, y, f"{r['success']}/{r['tested']}", va="center", fontsize=7)
    ax.set_yticks(ys, [r["configuration"] for r in items], fontsize=7)
    ax.set_xlim(0, 1)
    ax.set_xlabel("success" + (" (95 % Wilson interval)" if seed_set == "report"
                               else " on tune seeds (no rate)"))
    ax.grid(alpha=0.3, axis="x")
    picked = chosen(rows, summary["seed_list"])
    top = max(max((p[0] for p in r.get("curve") or [[0, 0]]), default=0) for r in picked.values())
    grid = np.linspace(0, max(top, 1), 80)[1:]
    for r in items:
        band = _band([picked[(r["configuration"], s)].get("curve") for s in r["seeds"]], grid)
        if band is None:
            continue
        (line,) = bx.plot(grid, band[1], lw=1.3, drawstyle="steps-post", label=r["configuration"])
        bx.fill_between(grid, band[0], band[2], color=line.get_color(), alpha=0.15, lw=0,
                        step="post")
    bx.set_xlabel("evaluations")
    bx.set_ylabel("best cost so far, final weights (median, quartiles)")
    bx.grid(alpha=0.3)
    if bx.lines:
        bx.legend(fontsize=6)
    else:                         # rows imported from records that kept no log
        bx.text(0.5, 0.5, "no learning curves in these rows", ha="center", va="center",
                transform=bx.transAxes, fontsize=9, color="0.4")
    fig.suptitle(f"{spec.title} — {seed_set} seeds", fontsize=9)
    fig.set_layout_engine("constrained")
    _save_png(fig, path, 110)
