"""Steer Mr. Star-Man's gait with Auslander's secondary terms (Table 3).

Time-based BSR with the serial search; `w_contact_distance` favours a
shuffle, `w_rotations` a cartwheel.  Prints the gait each run found.

    python examples/starman_styles.py
"""
from gpmotion import RunConfig, read_json, run

for style, weights in (("plain", {}), ("shuffle", {"w_contact_distance": 0.5}),
                       ("cartwheel", {"w_rotations": 1.0})):
    out = f"runs/example-starman/{style}"
    cfg = RunConfig(task="starman_travel", family="bsr-time", seed=0, params=weights,
                    search={"n_generations": 600})
    run(cfg, out, force=True, quiet=True)
    best = read_json(f"{out}/best.json", kind="best")
    print(f"{style:<10} " + "; ".join(best["facts"][:3]))
