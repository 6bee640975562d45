"""Machine and library versions printed with every benchmark table (shared by the
benchmark scripts)."""

from __future__ import annotations

import datetime as _dt
import os
import platform
from pathlib import Path


def machine() -> str:
    import numpy
    import scipy
    import sympy

    try:
        import symengine

        se = symengine.__version__
    except ImportError:  # pragma: no cover
        se = "not installed"
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{_dt.date.today().isoformat()}; {cpu}, {os.cpu_count()} cores "
            f"(shared with other jobs); {platform.system()} {platform.release()}; "
            f"Python {platform.python_version()}, NumPy {numpy.__version__}, "
            f"SciPy {scipy.__version__}, SymPy {sympy.__version__}, SymEngine {se}")
