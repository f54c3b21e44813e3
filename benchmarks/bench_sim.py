"""Simulator throughput (the script behind ``gpmotion bench``).

    python benchmarks/bench_sim.py [--figure lamp] [--controller sine|gp] [--json] [--quick]

See gpmotion/bench.py for what is measured and how.
"""
import sys

from gpmotion.bench import main

if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
