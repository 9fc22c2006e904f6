"""The contact-model interface: what every contact model of :mod:`gearfmu.contact.models` gets and returns.

:class:`ContactEnvironment` (pair, geometry, speed, lubricant, roughness, slice width,
executor settings), :class:`RoughnessSpec` (the ``[roughness]`` of a scene),
:class:`ContactStiffness` (the answer), :class:`ContactModel` (a registry entry), the film
parameter Lambda = h_min/sigma (:func:`film_parameter`) and the settings of the rough-film
grid (docs/ehl_mesh.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, List, Optional

import numpy as np

from ..common.vocabulary import FILM_FAILURE_POLICIES, FILM_TRANSIENT_MODES
from ..gear.hertz import reduced_modulus_Pa
from .roughness import wm_sigma_m, SEED000_LEVELS, make_flank_roughness
from ..ehl.fits import dowson_higginson_min_film
from ..ehl.mesh_film import contact_kinematics, FilmEnvironment


class ContactModelError(ValueError):
    """Bad contact-model input, or a film failure under ``on_failure = "error"``."""


#: full-film limit of the film parameter Lambda = h_min/sigma (Tallian 1967; Johnson,
#: Greenwood & Poon 1972; gearfmu.contact.fractal.FULL_FILM_LAMBDA)
FULL_FILM_PARAMETER = 3.0
#: contact positions (uniform over the path of contact, ends included) at which the rough
#: films are solved and between which the film stiffness is interpolated (docs/ehl_mesh.md)
DEFAULT_FILM_POSITION_NODES = 9
#: ratio of neighbouring load nodes of the film grid (geometric, anchored at the scene's
#: nominal line load) when no load range is known
FILM_LOAD_NODE_RATIO = 2.0
#: a stalled rough grid node is replaced by linear interpolation in position of the
#: rough/smooth ratio between the nearest converged nodes of the same slice and load
#: column when they are at most this many node spacings apart (an end node: the adjacent
#: node's ratio); otherwise the policy (smooth film) applies (fill_stalled_ratio)
STALL_FILL_MAX_SPAN = 3
#: rough load nodes over a known load range (ContactEnvironment.film_load_range_N_per_m,
#: set by the table builder: the load floor to the largest static slice load)
FILM_LOAD_NODES = 3
#: slices per film-grid node run in time for the transient correction (CHOICE of
#: docs/ehl_transient.md section 3: 4, spread evenly over the face; all when fewer)
FILM_TRANSIENT_SLICES = 4
#: time reductions of a transient run (docs/ehl_transient.md section 3): (b) "k_of_means" =
#: A B(<p_m>)/<h_m> (the table's CHOICE, the "central OFT" explanation of Zhao et al. 2022) and (a)
#: "mean_of_k" = <A B(p_m)/h_m>
FILM_TRANSIENT_REDUCTIONS = ("k_of_means", "mean_of_k")
#: start of the transient runs of ``film_transient = "film"`` (as gearfmu.assembly.direct_tvms):
#: the steady frozen-roughness film, or -- where that solve stalls (most level 3-4 nodes) --
#: the smooth film with the roughness ramped in over ramp_T = 1 b/u_s
#: (:func:`gearfmu.ehl.transient.solve_line_contact_transient`); window: the solver's default,
#: from ramp_T + T_wash over T_AVERAGE = 4 b/u_s
FILM_TRANSIENT_START = "auto"


@dataclass(frozen=True)
class RoughnessSpec:
    """W-M flank roughness (Zhao et al. 2022 eq 1).  ``D`` fractal dimension, ``G_m``
    characteristic scale (m; Table 2's G read in mm, docs/ehl.md), ``seed``
    of the random phases, ``f_max_per_m`` band limit (1/m), ``level`` the
    Table 2 level it came from (0 = custom), ``on_failure`` 'fractal_mixed' |
    'hertz' | 'error' | 'load_sharing' (JGP film-asperity load sharing,
    gearfmu.contact.load_sharing, docs/load_sharing.md) (where Lambda < ``full_film_parameter`` or the rough
    film fails), ``position_nodes``: contact positions of the film grid (0 =
    solve at every requested position), ``film_transient``: 'off' (default) |
    'correction' (transient film correction of the grid nodes, :data:`FILM_TRANSIENT_MODES`,
    docs/ehl_transient.md section 3; needs ``position_nodes`` >= 2), ``film_transient_reduction``:
    its time reduction, 'k_of_means' (b, default) | 'mean_of_k' (a)
    (:data:`FILM_TRANSIENT_REDUCTIONS`; a study option, not a scene key);
    'film': the node's rough film is the transient film (:meth:`RoughFilmGrid.ensure`), and
    ``film_parameter_screen``: None (default: the mode decides -- the Lambda screen is on for
    'off' / 'correction', off for 'film', where the transient solver decides whether a full
    film exists, docs/ehl_mesh.md "Transient films in the tables"), True or False (a study
    option, not a scene key)."""

    D: float
    G_m: float
    seed: int = 2022
    f_max_per_m: float = 1e4
    level: int = 0
    on_failure: str = "fractal_mixed"
    full_film_parameter: float = FULL_FILM_PARAMETER
    position_nodes: int = DEFAULT_FILM_POSITION_NODES
    film_transient: str = "off"
    film_transient_reduction: str = FILM_TRANSIENT_REDUCTIONS[0]
    film_parameter_screen: Optional[bool] = None

    def __post_init__(self):
        if self.on_failure not in FILM_FAILURE_POLICIES:
            raise ContactModelError(f"on_failure={self.on_failure!r}: must be one of "
                                    f"{', '.join(FILM_FAILURE_POLICIES)}")
        lam = self.full_film_parameter
        if not (isinstance(lam, (int, float)) and math.isfinite(lam) and lam >= 0):
            raise ContactModelError(f"full_film_parameter={lam!r}: must be finite and >= 0")
        k = self.position_nodes
        if int(k) != k or k < 0 or k == 1:
            raise ContactModelError(f"position_nodes={k!r}: must be 0 (every position) or an integer >= 2")
        if self.film_transient not in FILM_TRANSIENT_MODES:
            raise ContactModelError(f"film_transient={self.film_transient!r}: must be one of "
                                    f"{', '.join(repr(m) for m in FILM_TRANSIENT_MODES)}")
        if self.film_transient_reduction not in FILM_TRANSIENT_REDUCTIONS:
            raise ContactModelError(f"film_transient_reduction={self.film_transient_reduction!r}: must be one "
                                    f"of {', '.join(repr(m) for m in FILM_TRANSIENT_REDUCTIONS)}")
        if self.film_parameter_screen not in (None, True, False):
            raise ContactModelError(f"film_parameter_screen={self.film_parameter_screen!r}: must be None "
                                    "(the film_transient mode decides), True or False")
        if self.film_transient != "off" and k == 0:
            raise ContactModelError(f"film_transient={self.film_transient!r}: the transient films are "
                                    "stored on the film grid; needs position_nodes >= 2 (got 0)")

    @property
    def screens_film_parameter(self) -> bool:
        """Whether requests with Lambda < ``full_film_parameter`` go to the film-failure policy
        before any solve: ``film_parameter_screen`` when set, else True except for
        ``film_transient = 'film'`` (CHOICE, docs/ehl_mesh.md "Transient films in the tables":
        Zhao et al. 2022 treat all four levels as full film, and the transient films exist at
        Lambda 2-3; a film that collapses (h <= 0) still goes to the policy)."""
        if self.film_parameter_screen is not None:
            return bool(self.film_parameter_screen)
        return self.film_transient != "film"

    @staticmethod
    def from_level(level: int, **kw) -> "RoughnessSpec":
        """Zhao et al. 2022 Table 2 level 1-4 (:data:`gearfmu.contact.roughness.SEED000_LEVELS`)."""
        if level not in SEED000_LEVELS:
            raise ContactModelError(f"level={level!r}: seed 000 Table 2 has levels 1-4")
        lv = SEED000_LEVELS[level]
        return RoughnessSpec(D=lv.D, G_m=lv.G_m, level=int(level), **kw)


@dataclass
class ContactEnvironment:
    """Inputs shared by all requests (SI).  ``omega1_rad_s`` pinion speed;
    lubricant eta0 (Pa s, at the oil temperature), alpha (1/Pa), rho0 (kg/m^3)
    (None for 'hertz'); ``n_slices`` and ``width_m`` of a slice; ``roughness``
    for 'rough_ehl'; ``executor`` / ``max_workers`` / ``progress`` for the EHL
    solves; ``ehl_nodes``: EHL grid nodes (None: the solver's choice);
    ``film_load_anchor_N_per_m``: a load node of the rough film grid (N/m; the
    scene's nominal line load T/(r_b1 b); None: 1e5 N/m); ``film_load_range_N_per_m``:
    (lowest, highest) slice load the tables will ask for (N/m; the grid then puts
    :data:`FILM_LOAD_NODES` load nodes over it)."""

    pair: object
    geom: object
    omega1_rad_s: float
    n_slices: int
    width_m: float
    eta0_Pas: Optional[float] = None
    alpha_Pa_inv: Optional[float] = None
    rho0_kg_m3: Optional[float] = None
    roughness: Optional[RoughnessSpec] = None
    executor: object = None
    max_workers: Optional[int] = None
    progress: bool = False
    ehl_nodes: Optional[int] = None
    film_load_anchor_N_per_m: Optional[float] = None
    film_load_range_N_per_m: Optional[tuple] = None
    _flanks: object = field(default=None, repr=False)
    _grid: object = field(default=None, repr=False)

    def film_environment(self):
        for name in ("eta0_Pas", "alpha_Pa_inv", "rho0_kg_m3"):
            v = getattr(self, name)
            if v is None or not math.isfinite(v) or v < 0 or (v == 0 and name != "alpha_Pa_inv"):
                raise ContactModelError(f"{name}={v!r}: the EHL contact models need a lubricant "
                                        "(eta0 > 0, alpha >= 0, rho0 > 0)")
        return FilmEnvironment(E_prime_Pa=2.0 * reduced_modulus_Pa(self.pair), eta0_Pas=self.eta0_Pas,
                               alpha_Pa_inv=self.alpha_Pa_inv, rho0_kg_m3=self.rho0_kg_m3,
                               width_m=self.width_m, n_nodes=self.ehl_nodes)

    def film_grid_summary(self) -> Optional[dict]:
        """The summary of the rough film grid the contact model solved on this environment
        (:meth:`gearfmu.contact.rough_ehl.RoughFilmGrid.summary`); None when there is none."""
        return None if self._grid is None else self._grid.summary()

    def flanks(self):
        """The sampled flank roughness (made once, cached)."""
        if self._flanks is None:
            r = self.roughness
            if r is None:
                raise ContactModelError("roughness: 'rough_ehl' needs a RoughnessSpec")
            self._flanks = make_flank_roughness(self.geom, r.D, r.G_m, self.n_slices, r.seed,
                                                f_max_per_m=r.f_max_per_m)
        return self._flanks


#: what each ``status`` of a flagged contact request (``ContactStiffness.failures``) means and
#: which stiffness the tables hold there; the build and ``gearfmu tables`` print these words
FLAG_MEANINGS = {
    "full_film": "film parameter h_min/sigma >= 3, a full film: the mixed-lubrication stiffness, kept there, "
                 "overstates the asperity contact",
    "complete_contact": "asperities would touch over the whole nominal area: Hertz stiffness used",
    "low_film_parameter": "film parameter below the full-film limit: the scene's roughness on_failure model used",
    "stall": "rough EHL film did not converge: the on_failure model used",
    "collapse": "rough EHL film collapsed (h <= 0): the on_failure model used",
    "smooth film failed": "smooth EHL film did not converge: the on_failure model used",
}


@dataclass
class ContactStiffness:
    """Result of a contact model: ``k_N_per_m`` per request (N/m per slice),
    ``solves`` (EHL solves run), ``failures`` (dicts with s_m, slice, w_N_per_m,
    status, film_parameter, message), ``fallbacks`` (how many used Hertz)."""

    k_N_per_m: np.ndarray
    solves: int = 0
    failures: List[dict] = field(default_factory=list)
    fallbacks: int = 0


@dataclass(frozen=True)
class ContactModel:
    """A registered model: ``fn(env, s_m, slice_index, w_N_per_m) -> ContactStiffness``;
    ``load_dependent``: k depends on w (the tables then get a torque axis);
    ``needs_lubricant``."""

    name: str
    fn: Callable
    load_dependent: bool
    needs_lubricant: bool
    doc: str = ""


def _check(env, s_m, slice_index, w):
    s = np.asarray(s_m, dtype=float).ravel()
    n = np.asarray(slice_index).ravel().astype(int)
    w = np.asarray(w, dtype=float).ravel()
    if not (s.shape == n.shape == w.shape):
        raise ContactModelError("s_m, slice_index, w_N_per_m: need equal lengths")
    if np.any(~np.isfinite(s)):
        raise ContactModelError("s_m: contact positions must be finite")
    if np.any(~np.isfinite(w)) or np.any(w <= 0):
        raise ContactModelError("w_N_per_m: slice loads must be finite and > 0 (N/m)")
    if np.any(n < 0) or np.any(n >= env.n_slices):
        raise ContactModelError(f"slice_index: must lie in [0, {env.n_slices})")
    return s, n, w


def _key(x: float) -> float:
    return float(f"{x:.10g}")


def composite_sigma_m(spec: RoughnessSpec) -> float:
    """Composite RMS roughness sigma = sqrt(sigma1^2 + sigma2^2) (m) of the two flanks:
    both carry the W-M roughness of ``spec`` (same D, G), so sigma = sqrt(2) sigma_WM with
    sigma_WM the expected RMS height of the full W-M sum
    (:func:`gearfmu.contact.roughness.wm_sigma_m`, the convention that reproduces Zhao et al. 2022
    Table 2's Ra; CHOICE: the full band, not the band-limited profile the solver sees, since
    Lambda describes the real surfaces)."""
    return math.sqrt(2.0) * wm_sigma_m(spec.D, spec.G_m)


def film_parameter(env: "ContactEnvironment", s_m, w_N_per_m) -> np.ndarray:
    """Film parameter Lambda = h_min / sigma per request (1).

    h_min: Dowson & Higginson (1966) minimum film of the smooth line contact,
    h_min/R = 2.65 U^0.70 G^0.54 W^-0.13 (:func:`gearfmu.ehl.fits.dowson_higginson_min_film`)
    with R, u_s of the position (:func:`gearfmu.ehl.mesh_film.contact_kinematics`),
    W = w/(E' R), U = eta0 u_s/(E' R), G = alpha E'; sigma: :func:`composite_sigma_m`
    (Lambda as defined by Tallian 1967; full film above 3)."""
    if env.roughness is None:
        raise ContactModelError("roughness: the film parameter needs a RoughnessSpec")
    a = env.alpha_Pa_inv
    if a is None or not math.isfinite(a) or a <= 0:
        raise ContactModelError(f"alpha_Pa_inv={a!r}: the film parameter (Dowson-Higginson) needs alpha > 0")
    s = np.atleast_1d(np.asarray(s_m, dtype=float))
    w = np.broadcast_to(np.asarray(w_N_per_m, dtype=float), s.shape)
    Ep = 2.0 * reduced_modulus_Pa(env.pair)
    R, u, _ = contact_kinematics(env.geom, s, env.omega1_rad_s)
    h = np.array([Ri * dowson_higginson_min_film(wi / (Ep * Ri), env.eta0_Pas * ui / (Ep * Ri), a * Ep)
                  for Ri, ui, wi in zip(R.ravel(), u.ravel(), w.ravel())]).reshape(s.shape)
    return h / composite_sigma_m(env.roughness)
