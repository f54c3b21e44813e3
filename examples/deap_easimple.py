"""Evolve lamp_hop controllers with DEAP's own ``eaSimple`` loop.

gpmotion's toolbox gives DEAP individuals that are lists of trees (one per
lamp joint); its ``map`` turns eaSimple's per-individual evaluations into one
batched rollout per generation.  For checkpoints, cost reuse and a hall of
fame that respects the style phase-in, use ``gpmotion.run`` (GPSearch).
The best is saved as a controller file ``gpmotion replay`` reads.

    python examples/deap_easimple.py          # ~10 s after numba's first compile
"""
import random

import numpy as np
from deap import algorithms, tools

from gpmotion import evaluate_population, get_task, make_toolbox, save_controller

GENERATIONS = 5

task = get_task("lamp_hop", seconds=1.0)
toolbox = make_toolbox(task, generations=GENERATIONS)   # style terms phase in over 5 gens

random.seed(1)                      # DEAP's operators draw from `random`
population = toolbox.population(n=60)
hall = tools.HallOfFame(1)
stats = tools.Statistics(lambda ind: ind.fitness.values[0])
stats.register("min", np.min)
stats.register("median", np.median)

population, log = algorithms.eaSimple(population, toolbox, cxpb=0.9, mutpb=0.05,
                                      ngen=GENERATIONS, stats=stats, halloffame=hall,
                                      verbose=True)
best = hall[0]
# eaSimple's hall of fame compares costs from different style phases; re-score
# the winner under the full score (progress 1) to see what it is really worth.
full = evaluate_population(toolbox, [best], progress=1.0, assign=False)
print(f"best cost {best.fitness.values[0]:.4f} when found, "
      f"{full.costs[0]:.4f} with every style term on")
for joint, tree in zip(task.figure.actuator_names, best):
    print(f"  {joint}: {tree}")
save_controller("runs/deap_easimple_best.json", task, best, family=toolbox.family)
print("saved runs/deap_easimple_best.json: gpmotion replay runs/deap_easimple_best.json")
