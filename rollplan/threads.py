"""One BLAS/OpenMP thread per process for the command line, unless the user chose otherwise.

rollplan's arrays are small (a few hundred numbers): a multi-threaded BLAS gains nothing on them, and
its threads spin beside the work, which costs CPU time and, with ``batch --jobs N``, takes cores from
the other workers (``results/bench_batch.md`` measures it). Importing this module sets
``OPENBLAS_NUM_THREADS``, ``OMP_NUM_THREADS`` and ``MKL_NUM_THREADS`` to 1 where they are not set;
it must be imported before numpy, so :mod:`rollplan.cli` imports it first. The library itself
(``import rollplan``) leaves the environment alone: a program that uses it decides.
"""

from __future__ import annotations

import os

__all__ = ["THREAD_VARIABLES"]

#: The variables set to 1 when absent.
THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")

for _name in THREAD_VARIABLES:
    os.environ.setdefault(_name, "1")
