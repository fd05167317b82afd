"""Clash rule: two components' solids intersect beyond touching at a fitting.

Broad phase: axis-aligned bounding boxes, sweep and prune along x (sorted starts, then the y and z
intervals), so a thousand components cost O(n log n + pairs). Narrow phase: the overlap volume is
estimated by quasi-Monte Carlo inside the intersection of the two boxes: scrambled Sobol points
(scipy.stats.qmc) are tested for membership in both solids with exact analytic inside tests
(cylinder, cone frustum, torus sector, box, sphere, convex hull, thick plate). With ``N`` samples
and a hit share ``p`` the volume's standard error is bounded by the Monte Carlo one,
``V_box * sqrt(p (1 - p) / N)`` (Sobol points converge faster; the bound is conservative).
An overlap is an error only when it survives shrinking both solids by ``k_sigma`` standard
errors of the gap between their surfaces (the fits' centre and radius standard errors in
quadrature, a box's per local axis, split between the two: :func:`surface_stderr`,
:func:`erosions`); a shallower overlap (a pipe resting on a support, fitted a
millimetre into it) is an unverifiable warning. Components joined end to end (ends within ``touch_distance``) or linked in the scan are never
a clash; nor, with ``end_connections`` (the default), is a member whose axis *ends* inside the
other solid: a beam framing into a column or a nozzle into a tank is a connection (a fitting
merging placed is not spared so: it ends only at its ports, :data:`FITTINGS`). A clash is
one member passing through another, or lying along it: a member whose side, not its axis,
reaches into the other at its end, or one parallel to the other and off its line (pipes side by
side in a rack fitted into each other), does not end in it (:func:`ends_into`), whatever the
angle. Two same-size pipes on one axis are judged before those
exceptions: overlapping by more than a joint's scale (:data:`DUPLICATE_DIAMETERS` ODs or
``joint_distance``), or one wholly inside the other, they are a clash (a duplicate scan).
An insulated component's solid here is its envelope (:func:`asbuilt.insulation.envelope`): the
cladding was measured and takes up the room, so a beam through the lagging is a clash.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import qmc

from asbuilt.findings import Suggestion
from asbuilt.insulation import envelope
from asbuilt.model import Bend, Cross, Reducer, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere
from asbuilt.units import IMPERIAL, unit_factor

from ._context import Context, axis_of, ends_of, mm, stderr_value
from ._graph import end_pairs, linked_pairs

__all__ = ["CHECKS", "FITTINGS", "inside", "bounds", "candidate_pairs", "overlap_volume"]

#: Fittings merging places: they end only at their ports, which the pipes they join touch (a
#: joint, never a clash); a fitting's end inside anything else is not a connection (a coupling
#: through another at a cross, a pipe through a tee), so ``end_connections`` spares no fitting.
#: (A lateral is built as a tee-shaped fitting of type ``"tee"``.)
FITTINGS = ("coupling", "elbow", "tee", "cross", "reducer")


def _in_segment(
    points, start, end, radius_start, radius_end=None, erode=0.0, offset=None
) -> np.ndarray:
    """Inside a cylinder or cone frustum from ``start`` to ``end`` shrunk by ``erode`` metres;
    points (n, 3) m. ``offset`` (3,) m: an oblique frustum (eccentric reducer) whose axis steps
    sideways by it from start to end, its circles across ``end - start - offset``."""
    offset = np.zeros(3) if offset is None else np.asarray(offset, float)
    d = np.asarray(end) - np.asarray(start) - offset
    length = np.linalg.norm(d)
    u = d / length
    rel = points - start
    t = rel @ u
    f = np.clip(t / length, 0.0, 1.0)
    radial = np.linalg.norm(rel - np.outer(t, u) - np.outer(f, offset), axis=1)
    r_end = radius_start if radius_end is None else radius_end
    r = radius_start + (r_end - radius_start) * f
    return (t >= erode) & (t <= length - erode) & (radial <= r - erode)


def _in_bend(points, bend: Bend, erode=0.0) -> np.ndarray:
    c = bend.center
    a = bend.start - c
    b = bend.end - c
    big_r = np.linalg.norm(a)
    n = np.cross(a, b)
    if np.linalg.norm(n) < 1e-12:
        return np.zeros(len(points), bool)
    n /= np.linalg.norm(n)
    e1 = a / big_r
    e2 = np.cross(n, e1)
    rel = points - c
    h = rel @ n
    x, y = rel @ e1, rel @ e2
    rho = np.hypot(x, y)
    in_tube = (rho - big_r) ** 2 + h**2 <= max(bend.outer_radius - erode, 0.0) ** 2
    phi = np.arctan2(y, x) % (2 * np.pi)
    return in_tube & (phi <= np.radians(bend.angle_deg) + 1e-12)


def _in_plate(points, plane: Plane, thickness: float, erode=0.0) -> np.ndarray:
    outline = plane.outline
    if len(outline) < 3:
        return np.zeros(len(points), bool)
    d = (points - plane.point) @ plane.normal
    ok = np.abs(d) <= thickness / 2 - erode
    proj = points - np.outer(d, plane.normal)
    for i in range(len(outline)):
        p, q = outline[i], outline[(i + 1) % len(outline)]
        edge = np.cross(q - p, proj - p) @ plane.normal / max(np.linalg.norm(q - p), 1e-15)
        ok &= edge >= erode - 1e-12
    return ok


def inside(geometry, points, plate_thickness: float = 0.01, erode: float = 0.0) -> np.ndarray:
    """Whether each point (n, 3) metres lies inside the solid of ``geometry``; bool (n,).

    Pipes and fittings are solid (their bore counts as inside: a pipe through another's bore is
    still a clash). ``erode`` (metres) shrinks the solid by that much on every side first.
    """
    points = np.asarray(points, dtype=np.float64)
    g = geometry
    if isinstance(g, Cuboid):  # one erosion per local axis allowed
        local = (points - g.center) @ g.axes.T
        return np.all(np.abs(local) <= 0.5 * g.size - np.asarray(erode, dtype=np.float64), axis=1)
    e = float(np.max(erode))
    if isinstance(g, Straight):
        return _in_segment(points, g.start, g.end, g.outer_radius, erode=e)
    if isinstance(g, Reducer):
        return _in_segment(
            points, g.start, g.end, g.outer_radius_start, g.outer_radius_end, e, g.offset
        )
    if isinstance(g, Tee):
        return _in_segment(points, g.run_start, g.run_end, g.outer_radius, erode=e) | (
            _in_segment(points, g.center, g.branch_end, g.branch_outer_radius, erode=e)
        )
    if isinstance(g, Cross):
        return _in_segment(points, g.run_start, g.run_end, g.outer_radius, erode=e) | (
            _in_segment(points, g.branch_start, g.branch_end, g.branch_outer_radius, erode=e)
        )
    if isinstance(g, Bend):
        return _in_bend(points, g, e)
    if isinstance(g, Cylinder):
        s, end = g.ends
        return _in_segment(points, s, end, g.radius, erode=e)
    if isinstance(g, Sphere):
        return np.linalg.norm(points - g.center, axis=1) <= g.radius - e
    if isinstance(g, Hull):
        return g.distance(points) <= -e
    if isinstance(g, Plane):
        return _in_plate(points, g, plate_thickness, e)
    raise TypeError(f"unknown geometry {type(g).__name__}")


def bounds(geometry, plate_thickness: float = 0.01) -> np.ndarray | None:
    """Axis-aligned bounding box (2, 3) metres [min, max] of a solid, or None (unbounded)."""
    g = geometry

    def around(points, radius):
        points = np.atleast_2d(points)
        return np.array([points.min(axis=0) - radius, points.max(axis=0) + radius])

    if isinstance(g, Straight):
        return around([g.start, g.end], g.outer_radius)
    if isinstance(g, Reducer):
        return around([g.start, g.end], max(g.outer_radius_start, g.outer_radius_end))
    if isinstance(g, Tee | Cross):
        return around(
            [g.run_start, g.run_end, *g.outlets, g.center],
            max(g.outer_radius, g.branch_outer_radius),
        )
    if isinstance(g, Bend):
        a, b = g.start - g.center, g.end - g.center
        angles = np.linspace(0, 1, 33)
        theta = np.radians(g.angle_deg)
        n = np.cross(a, b)
        n /= np.linalg.norm(n)
        e2 = np.cross(n, a)
        arc = g.center + np.outer(np.cos(angles * theta), a) + np.outer(np.sin(angles * theta), e2)
        # the chord between samples bulges at most R (1 - cos(dtheta / 2))
        bulge = g.bend_radius * (1 - np.cos(theta / 64))
        return around(arc, g.outer_radius + bulge)
    if isinstance(g, Cylinder):
        return around(list(g.ends), g.radius)
    if isinstance(g, Cuboid):
        return around(g.corners, 0.0)
    if isinstance(g, Sphere):
        return around(g.center, g.radius)
    if isinstance(g, Hull):
        return around(g.vertices, 0.0)
    if isinstance(g, Plane):
        if len(g.outline) < 3:
            return None
        return around(g.outline, plate_thickness / 2)
    raise TypeError(f"unknown geometry {type(g).__name__}")


def candidate_pairs(boxes: np.ndarray) -> list[tuple[int, int]]:
    """Index pairs whose boxes (m, 2, 3) overlap: sweep and prune along x."""
    m = len(boxes)
    if m < 2:
        return []
    order = np.argsort(boxes[:, 0, 0], kind="stable")
    lo = boxes[order, 0, 0]
    pairs = []
    for rank, i in enumerate(order):
        stop = np.searchsorted(lo, boxes[i, 1, 0], side="right")
        for j in order[rank + 1 : stop]:
            if np.all(boxes[i, 0, 1:] <= boxes[j, 1, 1:]) and np.all(
                boxes[j, 0, 1:] <= boxes[i, 1, 1:]
            ):
                pairs.append((int(min(i, j)), int(max(i, j))))
    return pairs


def overlap_volume(
    ga,
    gb,
    box_a,
    box_b,
    samples: int = 4096,
    seed: int = 0,
    plate_thickness: float = 0.01,
    erode=0.0,
    erode_b=None,
):
    """Overlap volume of two solids by quasi-Monte Carlo.

    With ``erode`` > 0 both solids are first shrunk by that many metres on every side (the
    overlap that is left is beyond that much uncertainty in where their surfaces are);
    ``erode_b``, when given, is ``gb``'s own (``erode`` then ``ga``'s). A cuboid's may be one
    value per local axis, shape (3,) (see :func:`erosions`).

    Returns ``(volume m^3, standard error m^3, centroid (3,) m or None)``.
    """
    lo = np.maximum(box_a[0], box_b[0])
    hi = np.minimum(box_a[1], box_b[1])
    if np.any(hi <= lo):
        return 0.0, 0.0, None
    box_volume = float(np.prod(hi - lo))
    exponent = max(int(np.ceil(np.log2(max(samples, 2)))), 1)
    unit = qmc.Sobol(d=3, scramble=True, seed=seed).random_base2(exponent)
    points = lo + unit * (hi - lo)
    erode_b = erode if erode_b is None else erode_b
    hit = inside(ga, points, plate_thickness, erode) & inside(gb, points, plate_thickness, erode_b)
    n = len(points)
    share = float(hit.mean())
    volume = box_volume * share
    stderr = box_volume * float(np.sqrt(max(share * (1 - share), 1.0 / n) / n))
    centroid = points[hit].mean(axis=0) if hit.any() else None
    return volume, stderr, centroid


def surface_stderr(component):
    """Standard error (metres) of where a component's surface is; 0 without a fit (fittings
    placed by merging).

    Cylinders and other round or single-surface fits: their centre and radius standard errors in
    quadrature. Cuboids: one value per local axis, shape (3,), for the faces across that axis:
    a face is where the box's centre along the axis lies plus or minus half its size there, and
    the box's centre along an axis, the mid-point of its two faces, is known to half its size's
    standard error ``S_k`` when the faces are measured independently (never worse than the
    fit's 3-D centre error ``C``), so ``hypot(min(C, S_k / 2), S_k / 2)``. Not ``C`` and the
    largest ``S_k`` for every face: both are dominated by the long axis of a column or a beam,
    whose ends the scan window leaves uncertain by decimetres, which says nothing of where the
    faces a pipe passes through lie. A size known only as a lower bound (infinite standard error:
    the shots ran on past the scan window or stopped short of the edges) gives 0 there: the box
    is at least as long as drawn.
    """
    fit = component.fit
    if fit is None:
        return 0.0
    stderr = fit.stderr or {}
    centre = stderr_value(stderr, "center")
    centre = 0.0 if centre is None else centre
    radius = stderr_value(stderr, "radius")
    size = stderr.get("size")
    if radius is None and isinstance(fit.primitive, Cuboid) and size is not None:
        size = np.asarray(size, dtype=np.float64).ravel()
        if size.size == 1:
            size = np.repeat(size, 3)
        if size.size == 3 and isinstance(component.geometry, Cuboid):
            half = np.where(np.isfinite(size), 0.5 * size, 0.0)
            return np.hypot(np.minimum(centre if np.isfinite(centre) else np.inf, half), half)
    if radius is None:
        size = stderr_value(stderr, "size")
        radius = 0.5 * size if size is not None else 0.0
    return float(np.hypot(centre, radius))


def erosions(se_a, se_b, k: float):
    """How far (metres) to shrink each of two solids so that the overlap left is beyond ``k``
    standard errors of the gap between their surfaces: ``k s_a^2 / hypot(s_a, s_b)`` and
    ``k s_b^2 / hypot(s_a, s_b)``, which add up to ``k hypot(s_a, s_b)`` and leave an exact solid
    (a fitting merging placed, ``s = 0``) unshrunk. A per-axis ``s`` (a cuboid's, (3,)) meets the
    other solid's smallest, its erosion then being per axis too.
    """

    def shrink(own, other):
        own = np.asarray(own, dtype=np.float64)
        other = float(np.min(other))
        total = np.hypot(own, other)
        with np.errstate(invalid="ignore", divide="ignore"):
            out = np.where(total > 0, k * own**2 / np.where(total > 0, total, 1.0), 0.0)
        return float(out) if out.ndim == 0 else out

    return shrink(se_a, se_b), shrink(se_b, se_a)


def _across(erode, geometry, point) -> float:
    """The erosion (metres) across the face of ``geometry`` nearest ``point`` (the overlap's
    centroid): a cuboid's per-axis value there, else the one value."""
    values = np.asarray(erode, dtype=np.float64)
    if values.ndim == 0 or not isinstance(geometry, Cuboid) or point is None:
        return float(np.max(values))
    local = np.abs((np.asarray(point, dtype=np.float64) - geometry.center) @ geometry.axes.T)
    return float(values[int(np.argmin(0.5 * geometry.size - local))])


def member_ends(geometry) -> np.ndarray:
    """Where a member ends, shape (k, 3) metres: the axis end points of pipes, cylinders, cuboids
    (long axis) and reducers, a bend's ends, a tee's three ends and a cross's four; empty for the rest."""
    if isinstance(geometry, Reducer):  # its end centres (an eccentric one's are offset)
        return np.array([geometry.start, geometry.end])
    found = axis_of(geometry)
    if found is not None:
        axis, length, centre = found
        return np.array([centre - 0.5 * length * axis, centre + 0.5 * length * axis])
    ends = ends_of(geometry)
    return np.array(ends).reshape(-1, 3)


def _half_section(geometry) -> float:
    """Half the largest cross-section size of a member, metres (0 when it has none)."""
    if isinstance(geometry, (Straight, Bend)):
        return float(geometry.outer_radius)
    if isinstance(geometry, Reducer):
        return float(max(geometry.outer_radius_start, geometry.outer_radius_end))
    if isinstance(geometry, Tee | Cross):
        return float(geometry.outer_radius)
    if isinstance(geometry, Cylinder):
        return float(geometry.radius)
    if isinstance(geometry, Cuboid):
        return 0.5 * float(np.sort(geometry.size)[1])
    return 0.0


#: Directions probing a ball around a member's end (the 26 neighbours of a cube, normalised).
_PROBE = np.array(
    [
        [x, y, z]
        for x in (-1, 0, 1)
        for y in (-1, 0, 1)
        for z in (-1, 0, 1)
        if (x, y, z) != (0, 0, 0)
    ],
    dtype=np.float64,
)
_PROBE /= np.linalg.norm(_PROBE, axis=1)[:, None]


def _core(geometry) -> float:
    """Half the smallest cross-section size of a member, metres (0 when it has none): a round
    member's radius (a reducer's smaller one), a box's half its narrowest side across its long
    axis."""
    if isinstance(geometry, Straight):
        return float(geometry.outer_radius)
    if isinstance(geometry, Reducer):
        return float(min(geometry.outer_radius_start, geometry.outer_radius_end))
    if isinstance(geometry, Cylinder):
        return float(geometry.radius)
    if isinstance(geometry, Cuboid):
        return 0.5 * float(np.sort(geometry.size)[0])
    return 0.0


def _section_within(geometry, point, half: float) -> bool:
    """Whether a section of half size ``half`` (metres) centred on ``point`` (3,) and square to
    the long axis of ``geometry`` lies within its cross-section: a pipe nested in a larger one
    (a casing, a sleeve), a nozzle through a tank's head, a post in a pedestal."""
    found = axis_of(geometry)
    if found is None:
        return False
    axis, _, centre = found
    rel = np.asarray(point, dtype=np.float64) - centre
    if isinstance(geometry, Cuboid):
        local = np.abs(rel @ geometry.axes.T)
        across = np.abs(geometry.axes @ axis) < 0.5  # the two local axes across the long one
        return bool(np.all(local[across] + half <= 0.5 * geometry.size[across]))
    lateral = float(np.linalg.norm(rel - (rel @ axis) * axis))
    return lateral + half <= _core(geometry)


def _axis_ends(geometry) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(end (3,), outward unit (3,))`` for each end of a straight member (pipe, cylinder,
    cuboid along its long axis, reducer at its end centres); empty for the rest."""
    if isinstance(geometry, Reducer):
        return [(geometry.start, -geometry.direction), (geometry.end, geometry.direction)]
    found = axis_of(geometry)
    if found is None:
        return []
    axis, length, centre = found
    return [(centre - 0.5 * length * axis, -axis), (centre + 0.5 * length * axis, axis)]


def _shared_stretch(ga, gb) -> float:
    """Length (metres) of ``ga``'s axis that ``gb``'s axis runs beside (``gb``'s ends projected
    onto ``ga``'s axis, clipped to ``ga``)."""
    (ua, la, ca), (ub, lb, cb) = axis_of(ga), axis_of(gb)
    t = [float((cb + s * 0.5 * lb * ub - ca) @ ua) for s in (-1.0, 1.0)]
    return max(0.0, min(max(t), 0.5 * la) - max(min(t), -0.5 * la))


def ends_into(
    ga,
    gb,
    thickness: float = 0.01,
    parallel_deg: float = 10.0,
    joint_scale: float = 0.15,
) -> bool:
    """Whether member ``ga`` ends in or at solid ``gb`` (a beam framing into a column or meeting
    another beam at a corner, a nozzle into a tank, a pipe butting into the next): a connection,
    not a clash.

    An end counts when ``ga``'s axis, within its half section of the end either way, reaches
    into ``gb`` (the end is inside, or stops that short of it): a member ending *beside* another
    (its side, not its axis, in the other) does not end in it. A member within ``parallel_deg``
    of ``gb``'s long axis runs along it rather than into it: its end counts only when its section
    there lies within ``gb``'s cross-section (a pipe through a tank's head or inside a casing) or
    it continues ``gb``'s line (axes within the smaller member's core of each other, sharing at
    most ``max(the larger OD, joint_scale)`` of length: an in-line joint). Parallel pipes overlapping
    side by side along their length are therefore a clash, however near their ends lie.
    Geometries with ends but no straight axis (a bend, a tee) count when a point of the ball of
    their half section around an end is inside.
    """
    half = _half_section(ga)
    ends = _axis_ends(ga)
    if not ends:
        ends = member_ends(ga)
        if not len(ends):
            return False
        probes = np.concatenate([ends] + [ends + half * d for d in _PROBE])
        return bool(inside(gb, probes, thickness).any())
    # the axis from half a section inside the end to half a section beyond it, finely enough
    # for a plate's thickness
    count = int(np.clip(np.ceil(2.0 * half / max(0.5 * thickness, 1e-4)), 8, 256)) + 1
    steps = np.linspace(-half, half, count)
    along_b = axis_of(gb)
    parallel = False
    if along_b is not None:
        cos = abs(float(axis_of(ga)[0] @ along_b[0]))
        parallel = cos >= np.cos(np.radians(parallel_deg))
    for end, out in ends:
        if not inside(gb, end + np.outer(steps, out), thickness).any():
            continue
        if not parallel:
            return True
        if _section_within(gb, end, half):
            return True
        axis, _, centre = along_b
        rel = end - centre
        lateral = float(np.linalg.norm(rel - (rel @ axis) * axis))
        scale = max(DUPLICATE_DIAMETERS * 2.0 * max(half, _half_section(gb)), joint_scale)
        if lateral <= min(_core(ga), _core(gb)) and _shared_stretch(ga, gb) <= scale:
            return True
    return False


#: Straight members of one size may overlap along a shared axis by at most
#: ``max(DUPLICATE_DIAMETERS x OD, Tolerances.joint_distance)`` and still be one joint: fitted
#: extents end within noise of the last shot, merging treats facing ends up to ``joint_distance``
#: (0.15 m) apart as one joint, and a pipe pushed into a socket or bell enters it by at most about
#: one diameter. Beyond that (or when one lies wholly inside the other) the two are the same pipe
#: twice: a duplicate scan or two runs drawn over each other.
DUPLICATE_DIAMETERS = 1.0

#: Component types checked for duplicates (fittings are placed by merging, not scanned).
_DUPLICATE_TYPES = ("pipe", "cylinder")


def _segment(geometry):
    """``(start (3,), end (3,), radius)`` in metres of a straight or cylinder, else None."""
    if isinstance(geometry, Straight):
        radius = float(geometry.outer_radius)
    elif isinstance(geometry, Cylinder):
        radius = float(geometry.radius)
    else:
        return None
    start, end = ends_of(geometry)
    return start, end, radius


def _od_stderr(component) -> float:
    """Standard error (metres) of a component's fitted outside diameter; 0 when unknown."""
    se = stderr_value(component.fit.stderr, "radius") if component.fit is not None else None
    if se is not None:
        return 2.0 * se
    return float((component.snap or {}).get("od_stderr") or 0.0)


def collinear_overlap(ga, gb, max_angle_deg: float, end_tolerance: float = 0.0):
    """How far two straight members on one axis overlap along it.

    Parameters
    ----------
    ga, gb : Straight or Cylinder
        The members (metres).
    max_angle_deg : float
        Largest angle between the axes, degrees, for them to be "one axis".
    end_tolerance : float
        Metres by which the shorter member's ends may stick out of the longer and still count
        as wholly inside it.

    Returns
    -------
    tuple (overlap m, contained bool, centre (3,) m) or None
        None unless each axis runs inside the other solid (lateral offset at most the smaller
        radius at both ends of the shared stretch) and they share a stretch of positive length.
    """
    a, b = _segment(ga), _segment(gb)
    if a is None or b is None:
        return None
    (sa, ea, ra), (sb, eb, rb) = a, b
    la, lb = float(np.linalg.norm(ea - sa)), float(np.linalg.norm(eb - sb))
    if la < lb:
        (sa, ea, ra, la), (sb, eb, rb, lb) = (sb, eb, rb, lb), (sa, ea, ra, la)
    ua, ub = (ea - sa) / la, (eb - sb) / lb
    cos = float(ua @ ub)
    if abs(cos) < np.cos(np.radians(max_angle_deg)):
        return None
    t0, t1 = float((sb - sa) @ ua), float((eb - sa) @ ua)
    lo, hi = max(min(t0, t1), 0.0), min(max(t0, t1), la)
    if hi <= lo:
        return None
    radius = min(ra, rb)
    for t in (lo, hi):
        on_b = sb + ((t - t0) / cos) * ub  # the point of b's axis level with t on a's
        lateral = on_b - sa - float((on_b - sa) @ ua) * ua
        if np.linalg.norm(lateral) > radius:
            return None
    contained = min(t0, t1) >= -end_tolerance and max(t0, t1) <= la + end_tolerance
    return hi - lo, contained, sa + 0.5 * (lo + hi) * ua


def _check_duplicate(ctx: Context, a, b, touch: float) -> bool:
    """Emit a clash for two same-size straight members overlapping along one axis beyond a
    joint's scale (a duplicate scan); True when they are such a pair (handled here)."""
    if a.type not in _DUPLICATE_TYPES or b.type not in _DUPLICATE_TYPES:
        return False
    if a.fit is not None and a.fit is b.fit:  # pieces merging cut from one scanned pipe
        return False
    found = collinear_overlap(a.geometry, b.geometry, float(ctx.general("angle_snap_deg")), touch)
    if found is None:
        return False
    overlap, contained, centre = found
    od_a, od_b = 2.0 * _segment(a.geometry)[2], 2.0 * _segment(b.geometry)[2]
    window = max(
        float(ctx.general("diameter_tolerance")),
        3.0 * float(np.hypot(_od_stderr(a), _od_stderr(b))),
    )
    if abs(od_a - od_b) > window:
        return False  # different sizes on one axis: a sleeve or a casing, judged as a connection
    allowed = max(DUPLICATE_DIAMETERS * max(od_a, od_b), float(ctx.general("joint_distance")))
    if overlap <= allowed and not contained:
        return False
    first, second = sorted((a.id, b.id))
    noun = "pipe" if a.type == b.type == "pipe" else "object"
    where = (
        f"lies wholly inside {first} ({overlap:.2f} m)"
        if contained
        else f"overlaps {first} over {overlap:.2f} m"
    )
    ctx.emit(
        "clash",
        [first, second],
        f"{second} {where} along the same axis (same size, OD {mm(max(od_a, od_b))}): a "
        f"duplicate scan of the same {noun}? delete one or relabel",
        location=centre,
        measured=overlap,
        allowed=allowed,
        unit="m",
        suggestions=(
            Suggestion(
                f"delete {second} or {first} if it is a second scan of the same {noun}, or "
                "relabel it if it is another one; two runs: cut one back to where the other "
                "begins"
            ),
            Suggestion(
                f"if {first} and {second} are one pipe seen from two stations, link them "
                '("links": [["' + first + '", "' + second + '"]]), each with its "station": '
                "they are then fitted as one from all their shots"
            ),
        ),
    )
    return True


def _volume(ctx: Context, volume: float, se: float) -> str:
    """An overlap volume (m3) and its standard error for the message: cm3, or cubic inches
    when the model's display units are imperial (as its lengths are then inches)."""
    if ctx.model.units in IMPERIAL:
        cubic_inch = unit_factor("in") ** 3
        return f"{volume / cubic_inch:.3g} in3 (+- {se / cubic_inch:.2g})"
    return f"{volume * 1e6:.0f} cm3 (+- {se * 1e6:.0f})"


def check_clash(ctx: Context) -> None:
    slug = "clash"
    comps = list(ctx.model.components)
    thickness = float(ctx.general("plate_thickness"))
    touch = float(ctx.opt(slug, "touch_distance"))
    min_volume = float(ctx.opt(slug, "min_volume"))
    samples = int(ctx.opt(slug, "samples"))
    connections = bool(ctx.opt(slug, "end_connections"))
    keep, boxes, solid = [], [], []
    for comp in comps:
        shape = envelope(comp)  # an insulated pipe takes up the room of its cladding
        box = bounds(shape, thickness)
        if box is not None:
            keep.append(comp)
            boxes.append(box)
            solid.append(shape)
    if len(keep) < 2:
        return
    boxes = np.asarray(boxes)
    joined = set(end_pairs(keep, touch)) | linked_pairs(ctx.model)
    parallel = float(ctx.general("intended_angle_deg"))
    joint = float(ctx.general("joint_distance"))
    for i, j in candidate_pairs(boxes):
        a, b = keep[i], keep[j]
        # before the joint exceptions: a duplicate's ends touch or lie inside the other
        if _check_duplicate(ctx, a, b, touch):
            continue
        if frozenset((a.id, b.id)) in joined:
            continue
        ga, gb = solid[i], solid[j]
        if connections and (
            (a.type not in FITTINGS and ends_into(a.geometry, gb, thickness, parallel, joint))
            or (b.type not in FITTINGS and ends_into(b.geometry, ga, thickness, parallel, joint))
        ):
            continue
        volume, se, centroid = overlap_volume(
            ga,
            gb,
            boxes[i],
            boxes[j],
            samples,
            seed=i * 7919 + j,
            plate_thickness=thickness,
        )
        if volume <= min_volume:
            continue
        # the overlap that survives shrinking both solids by k standard errors of the gap between
        # their surfaces is certain; an overlap within that band may be fit noise (a pipe resting
        # on a support)
        erode_a, erode_b = erosions(surface_stderr(a), surface_stderr(b), ctx.k)
        margin = _across(erode_a, ga, centroid) + _across(erode_b, gb, centroid)
        certain = volume - ctx.k * se > min_volume
        if certain and margin > 0:
            kept, kept_se, _ = overlap_volume(
                ga,
                gb,
                boxes[i],
                boxes[j],
                samples,
                seed=i * 7919 + j,
                plate_thickness=thickness,
                erode=erode_a,
                erode_b=erode_b,
            )
            certain = kept - ctx.k * kept_se > min_volume
        first, second = sorted((a.id, b.id))
        ctx.emit(
            slug,
            [first, second],
            f"{first} and {second} intersect: {_volume(ctx, volume, se)} of overlap"
            + (" (insulation included)" if a.insulation or b.insulation else "")
            + (
                ""
                if certain
                else f", within the fits' uncertainty (the gap between their surfaces known to +- "
                f"{mm(margin / ctx.k) if ctx.k > 0 else mm(0.0)}, {ctx.k:g} standard errors "
                f"{mm(margin)})"
            ),
            location=centroid,
            measured=volume,
            allowed=min_volume,
            stderr=se,
            unit="m3",
            outcome="violation" if certain else "unverifiable",
            rescan=f"scan {first} and {second} where they meet",
            suggestions=(
                Suggestion(
                    f"check on site whether {first} and {second} really intersect, then reroute "
                    "one of them"
                ),
            ),
        )


CHECKS = {"clash": check_clash}
