"""FPU force and stiffness kernels: generated C vs hand C, numpy, sympy.lambdify, CasADi.

Run: ``python benchmarks/fpu_kernels.py --out bench-out [--quick]`` (same as ``mechgen bench``).
"""
import argparse
from pathlib import Path

from mechgen.bench.fpu import run_fpu_benchmarks

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="bench-out")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    run_fpu_benchmarks(out=Path(args.out), quick=args.quick)
