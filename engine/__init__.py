"""What any motion-controlled game needs: the fixed-step loop, budget accounting, sensor
sources, recordings and frames, the recognizer, and particle physics. Never imports `game`."""

__version__ = "0.1.0"

import os as _os

# One process, one thread (docs/architecture.md, "One process"). A multi-threaded BLAS only fights the 60 Hz loop
# for the cores: measured, a (60000 x 8) matrix-vector product in the recognizer took 98 us on
# one thread and 700 us on two on a loaded 2-core machine. Defaults only, and only effective
# when numpy has not been imported yet; set the variables to override.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")
