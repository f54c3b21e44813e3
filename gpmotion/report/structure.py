"""A controller's structure for the report: the picture its family draws
(GP: the trees, :mod:`gpmotion.treeplot`), or a BSR genome's rules as a table."""
from __future__ import annotations

import base64
import tempfile
from pathlib import Path

import numpy as np


def controller_view(family, genome) -> dict | None:
    if family.plot_file:
        with tempfile.TemporaryDirectory() as d:
            png = Path(d) / "structure.png"
            family.plot(png, genome)
            return {"kind": "image", "png": base64.b64encode(png.read_bytes()).decode("ascii"),
                    "caption": f"the {family.name} controller ({family.plot_file})"}
    data = family.to_json(genome)
    if isinstance(data, dict) and "theta0" in data and "tau" in data:
        return bsr_rules(family, data)
    return None


def bsr_rules(family, data: dict) -> dict:
    """One row per rule: its target angles θ₀ and time constants τ per joint and,
    for sense-based rules, the box it answers (centre μ ± half-width λ per sense)."""
    names = [family.task.figure.actuator_names[i] for i in family.actuators]
    theta = np.atleast_2d(data["theta0"])
    # τ is one time constant per rule (a row of R) or one per rule and joint
    tau = np.asarray(data["tau"], dtype=float).reshape(theta.shape[0], -1)
    tau_head = ([f"τ {n} (s)" for n in names] if tau.shape[1] == len(names) and tau.shape[1] > 1
                else ["τ (s)"] * tau.shape[1])
    head = ["rule"] + [f"θ₀ {n} (°)" for n in names] + tau_head
    mu, lam = data.get("mu"), data.get("lam")
    senses = []
    if mu is not None:
        idx = getattr(family, "sense_indices", None)
        all_names = family.task.figure.sense_names
        senses = ([all_names[int(i)] for i in idx] if idx is not None and len(idx) ==
                  np.atleast_2d(mu).shape[1] else
                  [f"sense {k}" for k in range(np.atleast_2d(mu).shape[1])])
        head += [f"{s} (μ ± λ)" for s in senses]
    rows = []
    for j in range(theta.shape[0]):
        row = [str(j)] + [f"{np.degrees(v):.1f}" for v in theta[j]] + [f"{v:.3f}" for v in tau[j]]
        if mu is not None:
            row += [f"{m:.3g} ± {w:.2g}" for m, w in zip(np.atleast_2d(mu)[j], np.atleast_2d(lam)[j])]
        rows.append(row)
    extra = []
    if "t_per" in data:
        extra.append(f"period t_per {float(data['t_per']):.3g} s")
    if data.get("durations") is not None:
        extra.append("rule durations " + ", ".join(f"{float(v):.3g}" for v in data["durations"]))
    return {"kind": "table", "head": head, "rows": rows,
            "caption": f"the {family.name} rules" + (f" ({'; '.join(extra)})" if extra else "")}
