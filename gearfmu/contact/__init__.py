"""Contact stiffness of a tooth pair: the model registry and its models.

Imports :mod:`gearfmu.gear`, :mod:`gearfmu.ehl`, :mod:`gearfmu.common`.

============  ===========================================================================
Module        Contents
============  ===========================================================================
models        the registry (hertz, smooth_ehl, rough_ehl, fractal_mixed), sliced TVMS
base          ContactEnvironment, RoughnessSpec, ContactStiffness, film parameter
rough_ehl     the rough-EHL model: film grid, failure policies, transient correction
fractal       fractal mixed-lubrication stiffness (seed 001)
load_sharing  film-asperity load sharing in a rough EHL line contact
roughness     Weierstrass-Mandelbrot flank roughness (seed 000 eq 1, Table 2)
============  ===========================================================================
"""
