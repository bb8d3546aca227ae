#!/usr/bin/env python3
"""The lbmpy 2.0 baseline for the LBM kernel benchmark: D2Q9 BGK (SRT), 1024x1024, two-array
pull, structure-of-arrays (fzyx) layout, OpenMP. Run it beside `cargo bench --bench lbm_mlups`
(bandwidth drifts 20-30 % between runs on shared machines, so compare in one sitting).

    pip install lbmpy==2.0
    OMP_NUM_THREADS=1 python3 scripts/lbmpy_baseline.py f64
    OMP_NUM_THREADS=2 python3 scripts/lbmpy_baseline.py f32
Prints the median MLUPS of 3 timed blocks (halo copies excluded, as in lbmpy's own figures).
"""
import sys
import time

import numpy as np
import pystencils as ps
from lbmpy import LBMConfig, LBMOptimisation, LBStencil, Method, Stencil, create_lb_update_rule

dtype = {"f64": "float64", "f32": "float32"}[sys.argv[1] if len(sys.argv) > 1 else "f64"]
n, q = 1024, 9
src, dst = ps.fields(f"src({q}), dst({q}): {dtype}[2D]", layout="fzyx")
rule = create_lb_update_rule(
    lbm_config=LBMConfig(stencil=LBStencil(Stencil.D2Q9), method=Method.SRT, relaxation_rate=1.6, compressible=True),
    lbm_optimisation=LBMOptimisation(symbolic_field=src, symbolic_temporary_field=dst),
)
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
kernel = ps.create_kernel(rule, config=cfg).compile()
w = np.array([4 / 9] + [1 / 9] * 4 + [1 / 36] * 4, dtype=dtype)
# fzyx: the population index is the slowest; numpy axis order stays (x, y, f).
a = np.ascontiguousarray(np.broadcast_to(w, (n + 2, n + 2, q)).transpose(2, 1, 0)).transpose(2, 1, 0)
b = a.copy(order="K")  # keep the fzyx strides (a plain copy() is C-contiguous)
for _ in range(5):
    kernel(src=a, dst=b)
    a, b = b, a
samples = []
for _ in range(3):
    steps = 50
    t = time.perf_counter()
    for _ in range(steps):
        kernel(src=a, dst=b)
        a, b = b, a
    samples.append(n * n * steps / (time.perf_counter() - t) / 1e6)
print(f"lbmpy BGK {sys.argv[1] if len(sys.argv) > 1 else 'f64'} two-array pull: {sorted(samples)[1]:.0f} MLUPS")
