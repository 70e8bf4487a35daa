"""Continua: clamped-free beam work-precision and Hermite assembly against scikit-fem.

Run: ``python benchmarks/beam_work_precision.py --out bench-out [--quick]`` (needs the
``bench`` extra: matplotlib for the plot, scikit-fem for the assembly comparison).
"""
import argparse
from pathlib import Path

from mechgen.bench.beam import run_field_benchmarks

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="bench-out")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    run_field_benchmarks(Path(args.out), quick=args.quick)
