"""The compiled kernels of every level (issue 20, item 2), decorated through
:mod:`chainmodel._numba` (the one switch). Kernels import nothing from ``models``, ``scene``,
``cli``, ``fmu`` or ``analysis``."""
