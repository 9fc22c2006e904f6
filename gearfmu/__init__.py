"""gearfmu: spur and helical gear mesh physics packaged as FMI 2.0 Co-Simulation FMUs.

Data flows one way: scene -> physics (geometry, stiffness, errors, loaded
mesh) -> tables (:mod:`gearfmu.tables`) -> native solver / FMU.
"""
__version__ = "0.1.0"
