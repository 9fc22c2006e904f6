"""Package discovery for setuptools (the metadata is in pyproject.toml).

Every folder under gearfmu/ is a package (namespace or regular), so new
subpackages and data folders (kernel C sources, runtime template, scenes)
install without editing a list.  The FMU interface spec lives at the top
level in modeldescription/ (by design) and installs as
gearfmu/modeldescription, so an installed gearfmu builds FMUs too.
"""
from setuptools import find_namespace_packages, setup

packages = find_namespace_packages(include=["gearfmu", "gearfmu.*"], exclude=["*.__pycache__"])
setup(
    packages=packages + ["gearfmu.modeldescription"],
    package_dir={"gearfmu.modeldescription": "modeldescription"},
    package_data={"": ["*.c", "*.h", "*.toml", "*.json", "*.py", "*.txt"]},
)
