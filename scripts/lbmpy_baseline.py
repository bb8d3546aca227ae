#!/usr/bin/env python3
"""The lbmpy 2.0 baseline for the LBM kernel benchmark: D2Q9, 1024x1024, structure-of-arrays
(fzyx) layout, AVX, OpenMP; BGK (SRT) or MRT, the two-array pull kernel or lbmpy's in-place AA
kernel (its even and odd time steps alternate, one field). Run it beside
`cargo bench --bench lbm_mlups` (bandwidth drifts 20-30 % between runs on shared machines, so
compare in one sitting).

    pip install lbmpy==2.0
    OMP_NUM_THREADS=1 python3 scripts/lbmpy_baseline.py f64 [srt|mrt] [pull|aa]
    OMP_NUM_THREADS=2 python3 scripts/lbmpy_baseline.py f32 srt aa
    GRAINFLOW_BENCH_N=4096 ...   another box edge (the same variable sets the bench's box)
Prints the median MLUPS of 3 timed blocks (halo copies excluded, as in lbmpy's own figures).
"""
import os
import sys
import time

import numpy as np
import pystencils as ps
from lbmpy import LBMConfig, LBMOptimisation, LBStencil, Method, Stencil, create_lb_update_rule

from lbmpy.advanced_streaming.utility import Timestep  # noqa: E402

precision = sys.argv[1] if len(sys.argv) > 1 else "f64"
method = sys.argv[2] if len(sys.argv) > 2 else "srt"
pattern = sys.argv[3] if len(sys.argv) > 3 else "pull"
dtype = {"f64": "float64", "f32": "float32"}[precision]
n, q = int(os.environ.get("GRAINFLOW_BENCH_N", "1024")), 9  # the bench's box edge
src, dst = ps.fields(f"src({q}), dst({q}): {dtype}[2D]", layout="fzyx")


def config(timestep):
    kind = {"srt": dict(method=Method.SRT, relaxation_rate=1.6),
            "mrt": dict(method=Method.MRT, relaxation_rates=[1.6, 1.4, 1.4, 1.2])}[method]
    extra = dict(streaming_pattern="aa", timestep=timestep) if pattern == "aa" else {}
    return LBMConfig(stencil=LBStencil(Stencil.D2Q9), compressible=True, **kind, **extra)


def rule(timestep):
    opt = LBMOptimisation(symbolic_field=src) if pattern == "aa" else LBMOptimisation(
        symbolic_field=src, symbolic_temporary_field=dst)
    return create_lb_update_rule(lbm_config=config(timestep), lbm_optimisation=opt)

from pystencils.codegen.config import CpuOptions, OpenMpOptions, VectorizationOptions  # noqa: E402
from pystencils.backend.platforms import X86VectorCpu, X86VectorArch  # noqa: E402,F401

cfg = ps.CreateKernelConfig(
    target=ps.Target.X86_AVX,
    default_dtype=dtype,
    cpu=CpuOptions(
        openmp=OpenMpOptions(enable=True),
        vectorize=VectorizationOptions(enable=True, assume_inner_stride_one=True),
    ),
)
if pattern == "aa":
    kernels = [ps.create_kernel(rule(t), config=cfg).compile() for t in (Timestep.EVEN, Timestep.ODD)]
else:
    kernels = [ps.create_kernel(rule(Timestep.BOTH), config=cfg).compile()]
w = np.array([4 / 9] + [1 / 9] * 4 + [1 / 36] * 4, dtype=dtype)
# fzyx: the population index is the slowest; numpy axis order stays (x, y, f).
a = np.ascontiguousarray(np.broadcast_to(w, (n + 2, n + 2, q)).transpose(2, 1, 0)).transpose(2, 1, 0)
b = a.copy(order="K")  # keep the fzyx strides (a plain copy() is C-contiguous)
step = 0


def advance():
    global a, b, step
    if pattern == "aa":
        kernels[step % 2](src=a)
    else:
        kernels[0](src=a, dst=b)
        a, b = b, a
    step += 1


for _ in range(6):
    advance()
samples = []
for _ in range(3):
    steps = max(4, 2 * (25 * 1024 * 1024 // (n * n)))  # even: AA alternates
    t = time.perf_counter()
    for _ in range(steps):
        advance()
    samples.append(n * n * steps / (time.perf_counter() - t) / 1e6)
name = {"pull": "two-array pull", "aa": "in-place AA"}[pattern]
print(f"lbmpy {method.upper()} {precision} {name}: {sorted(samples)[1]:.0f} MLUPS")
