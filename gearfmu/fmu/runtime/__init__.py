"""The pythonfmu runtime: ``gearfmu_slave.py`` is the slave class copied into every
pythonfmu FMU (it loads the C kernel with ctypes), ``kernel_api.py`` the table of the kernel's C
functions it binds the library with (copied beside it; the tests and benchmarks bind the kernel
with it too).  Both run inside the FMU, without gearfmu, so they import nothing from the package
(checked by tests/project/test_architecture.py).
"""
