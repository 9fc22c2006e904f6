"""Shared by every layer; imports nothing from gearfmu (the bottom layer).

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
============  ===============================================================================
"""
