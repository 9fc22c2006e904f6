"""The pythonfmu runtime: ``gearfmu_slave.py`` is the slave class copied into every
pythonfmu FMU (it loads the C kernel with ctypes).  It runs inside the FMU, without gearfmu,
so it imports nothing from the package (checked by tests/test_architecture.py).
"""
