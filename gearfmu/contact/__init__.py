"""Contact stiffness of a tooth pair: the model registry and its models.

Imports :mod:`gearfmu.gear`, :mod:`gearfmu.ehl`, :mod:`gearfmu.common`.

Exports (loaded with their module on first use): the registry ``get_contact_model``,
``register_contact_model``; ``ContactEnvironment``, ``RoughnessSpec``, ``ContactStiffness``,
``ContactModel``, ``ContactModelError``, ``film_parameter``; ``make_flank_roughness``.  The fractal
and load-sharing models are used through the registry; their details are in their modules.

============  ===========================================================================
Module        Contents
============  ===========================================================================
models        the registry (hertz, smooth_ehl, rough_ehl, fractal_mixed), sliced TVMS
base          ContactEnvironment, RoughnessSpec, ContactStiffness, film parameter
rough_ehl     the rough-EHL model: film grid, failure policies, transient correction
fractal       fractal mixed-lubrication stiffness (Xu, Shi & Fan 2023)
load_sharing  film-asperity load sharing in a rough EHL line contact
roughness     Weierstrass-Mandelbrot flank roughness (Zhao et al. 2022 eq 1, Table 2)
============  ===========================================================================
"""
from ..common.exports import lazy_exports

_EXPORTS = {
    "get_contact_model": "models", "register_contact_model": "models",
    **dict.fromkeys(("ContactEnvironment", "RoughnessSpec", "ContactStiffness", "ContactModel",
                     "ContactModelError", "film_parameter"), "base"),
    "make_flank_roughness": "roughness",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
