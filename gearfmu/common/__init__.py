"""Shared by every layer; imports nothing from gearfmu (the bottom layer).

Exports (loaded with their module on first use, :mod:`gearfmu.common.exports`): the run settings
``RunSettings``, ``GearboxRunSettings``, ``RunSettingsError``, ``default_output_interval_s``;
``finite_number``; ``RPM_TO_RAD_S``; ``make_executor``, ``cluster``; ``progress_bar``, ``notice``,
``ticking``; ``read_archive``, ``read_text``, ``ArchiveError``.  The option strings are read from
:mod:`gearfmu.common.vocabulary` by name (``vocabulary.CONTACT_MODELS``).

============  ===============================================================================
Module        Contents
============  ===============================================================================
vocabulary    every option string: contact models, damping models, integrators, runtimes, ...
checks        finite_number: the one input check of the physics and the solvers
settings      RunSettings (a pair run), GearboxRunSettings: the run settings, checked once;
              default_output_interval_s
units         RPM_TO_RAD_S
executors     make_executor: in-process, process pool or Dask cluster; cluster(), --scheduler
progress      progress_bar: the one progress reporter (tqdm on stderr)
user_files    files a user hands over: read_archive (zip, every member checked), read_text
cache         gearfmu's file cache: content-addressed entries, checked on read
jit           cache_is_cold: whether numba's cache holds the compiled kernels
topology      the topology of a drivetrain: parts, links, bodies, the tree and its rules
exports       lazy_exports: a package's public names, loaded on first use
============  ===============================================================================
"""
from .exports import lazy_exports

_EXPORTS = {
    **dict.fromkeys(("RunSettings", "GearboxRunSettings", "RunSettingsError", "default_output_interval_s"),
                    "settings"),
    "finite_number": "checks",
    "RPM_TO_RAD_S": "units",
    "make_executor": "executors", "cluster": "executors",
    "progress_bar": "progress", "notice": "progress", "ticking": "progress",
    "read_archive": "user_files", "read_text": "user_files", "ArchiveError": "user_files",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
