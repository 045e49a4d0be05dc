"""The machine a benchmark ran on, in one line, for its printout.

Figures move with the CPU: its model and vector instructions decide the compiled core's
speed, and NumPy's OpenBLAS picks its kernels by it, which decides the last bits of the
exact integrator's setup (docs/architecture.md) and so the details of a rattling ball's
exact run. Each benchmark that docs/performance.md quotes prints this line first.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np  # noqa: F401 (loads NumPy's BLAS, which threadpool_info reports)
from threadpoolctl import threadpool_info


def _cpu() -> tuple[str, str]:
    """The CPU's model name and its widest x86 vector extension ('' where unknown)."""
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return "", ""
    model = next((line.split(":", 1)[1].strip() for line in text.splitlines()
                  if line.startswith("model name")), "")
    flags = next((set(line.split(":", 1)[1].split()) for line in text.splitlines()
                  if line.startswith("flags")), set())
    isa = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else ""
    return model, isa


def describe() -> str:
    """'N cores, <CPU model> (<ISA>), BLAS <api> <kernels>, load L'."""
    model, isa = _cpu()
    cpu = f"{model} ({isa})" if model and isa else model or "CPU unknown"
    blas = sorted({f"{i.get('internal_api', '?')} {i.get('architecture', '?')}"
                   for i in threadpool_info() if i.get("user_api") == "blas"})
    return (f"{os.cpu_count()} cores, {cpu}, BLAS {', '.join(blas) or 'not loaded'}, "
            f"load {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    print(describe())
