"""What an evaluator hands a search: :class:`Evaluation`, the scores of a batch."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Evaluation:
    """Scores of a batch: costs (lower is better) and why."""
    costs: np.ndarray                    # float64[n]
    success: np.ndarray                  # bool[n]
    failed: np.ndarray                   # bool[n] diverged simulations
    measures: dict[str, np.ndarray]      # raw term values [n]
    extras: list | None = None           # per-genome data a search keeps (BSR: sense trajectories)

    @staticmethod
    def concat(parts: list["Evaluation"]) -> "Evaluation":
        extras = None if any(p.extras is None for p in parts) else [x for p in parts for x in p.extras]
        return Evaluation(np.concatenate([p.costs for p in parts]),
                          np.concatenate([p.success for p in parts]),
                          np.concatenate([p.failed for p in parts]),
                          {k: np.concatenate([p.measures[k] for p in parts]) for k in parts[0].measures},
                          extras)

    @staticmethod
    def of_costs(costs, extras=None) -> "Evaluation":
        """Bare costs (a toy objective, a test): nothing solved or failed, no measures."""
        c = np.array(costs, dtype=np.float64).ravel()
        return Evaluation(c, np.zeros(c.size, bool), np.zeros(c.size, bool), {},
                          None if extras is None else list(extras))
