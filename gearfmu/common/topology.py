"""The topology of a drivetrain: parts joined by rigid links, elastic shafts and gear meshes.

One definition, used by the drivetrain scene reader (problems reported with the scene's key
paths) and by the gearbox model built in code (:mod:`gearfmu.gearbox.model`), which may not
import each other.

A drivetrain is a set of named *parts* (``motor``, ``load``, ``<stage>.pinion``,
``<stage>.gear``) and *links* between two parts: ``rigid`` (the two parts become one body),
``shaft`` (an elastic shaft), ``mesh`` (a gear mesh, first part the pinion, the driving
member) and ``planetary`` (a planetary stage between its two free ports, either of them
upstream; docs/planetary.md).  The rules (docs/gearbox.md "Topology"):

* the parts joined by rigid links form the *bodies*;
* the bodies and the elastic links (shafts and meshes) form a tree: every body is reached from
  the root (the motor's body), and no link closes a loop -- so the drivetrain has one kinematic
  degree of freedom;
* every mesh is entered from its pinion: walking from the root, the pinion's body comes before
  the gear's (the pinion is the driving member of its stage);
* no link joins a part, or a body, to itself.

:func:`drivetrain_tree` returns the bodies in breadth-first order from the root (body 0 is the
root's), the links in that order with their direction, and every problem found.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

__all__ = ["LINK_KINDS", "Tree", "drivetrain_tree", "willis_ratio", "planetary_sun_torque"]

#: the kinds of link between two parts
LINK_KINDS = ("rigid", "shaft", "mesh", "planetary")


@dataclass(frozen=True)
class Tree:
    """The result of :func:`drivetrain_tree`.

    ``bodies``: per body the names of its parts (body 0 holds the root part; bodies in
    breadth-first order from it, children in link order); ``body_of``: part name -> body
    index; ``edges``: the elastic links (shafts and meshes) in breadth-first order, each as
    ``(link index, upstream body, downstream body)`` with the upstream body nearer the root;
    ``parent``: per body the edge index into ``edges`` that reaches it (-1 for body 0);
    ``problems``: ``(link index or None, part name or None, reason)`` for every rule broken
    (empty when the drivetrain is valid; the other fields are then only partly filled)."""

    bodies: Tuple[Tuple[str, ...], ...]
    body_of: Dict[str, int]
    edges: Tuple[Tuple[int, int, int], ...]
    parent: Tuple[int, ...]
    problems: Tuple[Tuple[Optional[int], Optional[str], str], ...] = field(default=())

    def path(self, a: int, b: int) -> List[int]:
        """Indices into ``edges`` of the links on the path between bodies a and b (in any
        order of walking); empty when a == b."""
        def up(x):
            out = []
            while x != 0:
                e = self.parent[x]
                out.append(e)
                x = self.edges[e][1]
            return out
        ua, ub = up(a), up(b)
        sa, sb = set(ua), set(ub)
        return [e for e in ua if e not in sb] + [e for e in ub if e not in sa]


def _find(parent: List[int], i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


def drivetrain_tree(parts: Sequence[str], links: Sequence[Tuple[str, str, str]], root: str) -> Tree:
    """Bodies, link order and problems of a drivetrain (module docstring).

    ``parts``: the part names (unique); ``links``: ``(kind, part a, part b)`` with ``kind`` in
    :data:`LINK_KINDS` (a mesh: a = pinion, b = gear); ``root``: the part the walk starts from
    (the motor).  Names not in ``parts`` must be checked by the caller (they raise KeyError)."""
    index = {p: i for i, p in enumerate(parts)}
    problems: List[Tuple[Optional[int], Optional[str], str]] = []
    # rigid links first: the parts of one body
    uf = list(range(len(parts)))
    for li, (kind, a, b) in enumerate(links):
        if kind not in LINK_KINDS:
            raise ValueError(f"link kind {kind!r} not one of {LINK_KINDS}")
        if a == b:
            problems.append((li, None, f"joins {a!r} to itself"))
            continue
        if kind == "rigid":
            ra, rb = _find(uf, index[a]), _find(uf, index[b])
            if ra == rb:
                problems.append((li, None, f"closes a loop: {a!r} and {b!r} are already joined rigidly"))
            else:
                uf[rb] = ra
    group = [_find(uf, i) for i in range(len(parts))]
    # the elastic links between the rigid groups: a tree?
    uf2 = {g: g for g in set(group)}
    adj: Dict[int, List[Tuple[int, int]]] = {g: [] for g in uf2}
    for li, (kind, a, b) in enumerate(links):
        if kind == "rigid" or a == b:
            continue
        ga, gb = group[index[a]], group[index[b]]
        if ga == gb:
            problems.append((li, None, f"joins {a!r} and {b!r}, which are one rigid body (rigid shafts join them)"))
            continue
        ra, rb = _find_d(uf2, ga), _find_d(uf2, gb)
        if ra == rb:
            problems.append((li, None, f"closes a loop between {a!r} and {b!r}: the drivetrain must be a tree "
                                       "(one kinematic degree of freedom)"))
            continue
        uf2[rb] = ra
        adj[ga].append((li, gb))
        adj[gb].append((li, ga))
    # breadth-first from the root's body
    g0 = group[index[root]]
    order = [g0]
    body_index = {g0: 0}
    edges: List[Tuple[int, int, int]] = []
    parent = [-1]
    orientation = []  # reported only without loops (with a loop the walking direction is arbitrary)
    k = 0
    while k < len(order):
        g = order[k]
        for li, h in sorted(adj[g]):
            if h in body_index:
                continue
            body_index[h] = len(order)
            order.append(h)
            edges.append((li, body_index[g], body_index[h]))
            parent.append(len(edges) - 1)
            kind, a, b = links[li]
            if kind == "mesh" and group[index[a]] != g:
                orientation.append((li, None, f"the gear {b!r} lies on the motor side of the pinion {a!r}: the pinion "
                                           "is the driving member of its stage (swap the stage's gears, or check "
                                           "the shafts)"))
        k += 1
    if not problems:
        problems += orientation
    for i, p in enumerate(parts):
        if group[i] not in body_index:
            problems.append((None, p, f"not connected to {root!r} (every part must be reached through shafts "
                                      "and meshes)"))
    bodies = [tuple(p for i, p in enumerate(parts) if group[i] == g) for g in order]
    body_of = {p: body_index[group[i]] for i, p in enumerate(parts) if group[i] in body_index}
    return Tree(bodies=tuple(bodies), body_of=body_of, edges=tuple(edges), parent=tuple(parent),
                problems=tuple(problems))


def _find_d(parent: Dict[int, int], i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


def willis_ratio(held: str, up: str, down: str, sun: float, ring: float) -> float:
    """Speed of port ``down`` over speed of port ``up`` of a planetary stage whose port ``held`` stands
    still (ports 'sun', 'carrier', 'ring'; every speed in the stage's one sense).  ``sun``, ``ring``:
    the sun's and ring's tooth counts or base radii (one base pitch: the same ratio).  Willis' equation
    z_s (w_s - w_c) + z_r (w_r - w_c) = 0 with the held port's w = 0."""
    if held == "ring":
        rel = {"sun": 1.0, "carrier": sun / (sun + ring)}
    elif held == "sun":
        rel = {"ring": 1.0, "carrier": ring / (sun + ring)}
    else:
        rel = {"sun": 1.0, "ring": -sun / ring}
    return rel[down] / rel[up]


def planetary_sun_torque(port: str, torque: float, sun: float, ring: float) -> float:
    """The sun's external torque in steady state when port ``port`` takes the external torque
    ``torque`` (N*m): the external torques on sun, ring and carrier stand in the ratio
    z_s : z_r : -(z_s + z_r) (their sum and the planets' balance vanish).  ``sun``, ``ring`` as for
    :func:`willis_ratio`."""
    share = {"sun": sun, "ring": ring, "carrier": -(sun + ring)}
    return torque * sun / share[port]

