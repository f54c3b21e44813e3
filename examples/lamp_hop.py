"""Evolve a hopping desk lamp from Python (what `gpmotion run lamp_hop` does).

    python examples/lamp_hop.py [OUT_DIR]
"""
import sys

from gpmotion import RunConfig, load_controller, replay_genome, run

out = sys.argv[1] if len(sys.argv) > 1 else "runs/example-lamp-hop"
cfg = RunConfig(task="lamp_hop", family="gp", seed=1, params={"distance": 0.4},
                search={"population": 200, "generations": 30})
best, cost, rundir = run(cfg, out, force=True)
task, family, actuation, genome, record = load_controller(rundir.path)
traj, costs, measures, ok = replay_genome(task, family, actuation, genome)
for row in task.breakdown(measures, 0):
    print(f"{row['term']:<10} {row['value']:8.3f} × {row['weight']:.2f}")
print("solved" if ok[0] else "not solved", "—", "; ".join(task.describe(traj, measures)))
print(f"pictures: {rundir.path}/filmstrip.png, {rundir.path}/motion.gif")
