"""The shapes of spool fittings from the sizes they join: reducer cones, tee dimensions and
geometry, whether a reducing elbow is a B16.9 one, and the words merging's notes use for them.

Private helper of :mod:`asbuilt.merge.spool` (which builds and places the fittings); each
function takes the :class:`~asbuilt.merge.spool.PipeSpec` of the pipes a fitting joins.
Numpy only; metres.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from asbuilt.model import Reducer, Tee

from .reducers import nps_order, reducing_elbow_ends, reducing_tee_dims

if TYPE_CHECKING:
    from .spool import PipeSpec

#: Bends within this many degrees of 45 use the catalog's 45 degree elbow centre-to-end; an
#: elbow within it of 45 or 90 degrees, or a tee's branch within it of square, is a B16.9
#: fitting (regularisation makes angles within ``angle_snap_deg``, 2, exact). Any other angle
#: is built (a 90 degree elbow cut to angle is real practice) but said to be non-standard.
ELBOW45_WINDOW_DEG = 2.0

__all__ = [
    "ELBOW45_WINDOW_DEG",
    "TRIM_SURFACE_TOLERANCE",
    "reducing_elbow_source",
    "flat_word",
    "reducer_cone",
    "same_size",
    "size_text",
    "tee_dims",
    "tee_geometry",
    "tee_solid",
]

#: A trimmed pipe end's shots within this (metres) of the fitting's own surface could be shots
#: of the fitting: three times the 2 mm prior range noise, the fits' outlier cutoff. A trim no
#: longer than the stretch over which the fitting's surface stays this close to the pipe's
#: cylinder (``_Builder.allowance``, set where each fitting is built) gets no note: an
#: operator's window that takes in a tee's or an elbow's first centimetres puts those shots on
#: the pipe.
TRIM_SURFACE_TOLERANCE = 0.006


def same_size(a: PipeSpec, b: PipeSpec) -> bool:
    return a.run == b.run or abs(a.od - b.od) < 1e-9


def reducer_cone(start, end, first: PipeSpec, second: PipeSpec, length: float, offset=None):
    """A reducer from ``first``'s size at ``start`` to ``second``'s at ``end`` ((3,) m each;
    ``offset`` (3,) m, eccentric, or None) and the trim allowance (m) of the pipes meeting it:
    the cone leaves either pipe's cylinder at its slope, half the step in OD over its length."""
    slope = abs(first.od - second.od) / (2.0 * max(length, 1e-9))
    allowance = min(TRIM_SURFACE_TOLERANCE / max(slope, 1e-9), length)
    # each end has its pipe's wall (B16.9 reducers are made to each end's schedule), so the
    # bore runs on from each pipe's; solid (0) throughout when either schedule is unknown
    hollow = bool(first.wall and second.wall)
    geometry = Reducer(
        start=start,
        end=end,
        outer_radius_start=0.5 * first.od,
        outer_radius_end=0.5 * second.od,
        wall_start=first.wall if hollow else 0.0,
        wall_end=second.wall if hollow else 0.0,
        offset=np.zeros(3) if offset is None else offset,
    )
    return geometry, allowance


def flat_word(flat) -> str:
    """``"top"``, ``"bottom"`` or ``"side"`` for an eccentric reducer's flat side (3,)."""
    if flat is None:
        return "none"
    if flat[2] > 1 - 1e-9:
        return "top"
    if flat[2] < -1 + 1e-9:
        return "bottom"
    return "side"


def tee_dims(run: PipeSpec, branch: PipeSpec) -> tuple[float, float, bool]:
    """``(C, M, paired)``: the centre-to-end of run and outlet (metres) of the tee joining the
    run pipe ``run`` to the outlet pipe ``branch``. A reducing outlet the fittings table lists
    (ASME B16.9 Table 8, :func:`.reducers.reducing_tee_dims`) has its pair's own (NPS 6 x 2 1/2:
    C 143, M 121 mm; ``paired`` True); any other tee the equal tee's of the run size."""
    if not same_size(run, branch) and branch.od < run.od:
        pair = reducing_tee_dims(run.dims.source, run.nominal, branch.nominal)
        if pair is not None:
            return pair[0], pair[1], True
    return run.dims.tee_run, run.dims.tee_outlet, False


def tee_geometry(center, run_dir, branch_dir, run: PipeSpec, branch: PipeSpec):
    c_run, c_out, _ = tee_dims(run, branch)
    return tee_solid(
        center,
        center - c_run * run_dir,
        center + c_run * run_dir,
        center + c_out * branch_dir,
        run,
        branch,
    )


def tee_solid(center, run_start, run_end, branch_end, run: PipeSpec, branch: PipeSpec) -> Tee:
    """A tee (or a lateral's tee-shaped fitting) between the given points ((3,) m each) with
    ``run``'s size on the run and ``branch``'s on the outlet."""
    # the run's wall on the run, the outlet pipe's on the outlet (as B16.9 reducing tees are
    # made); solid (0) throughout when either schedule is unknown
    hollow = bool(run.wall and branch.wall)
    return Tee(
        center=center,
        run_start=run_start,
        run_end=run_end,
        branch_end=branch_end,
        outer_radius=0.5 * run.od,
        branch_outer_radius=0.5 * branch.od,
        wall=run.wall if hollow else 0.0,
        branch_wall=branch.wall if hollow else 0.0,
    )


def size_text(p: PipeSpec) -> str:
    return f"NPS {p.nominal}" if p.nominal else f"OD {p.od * 1000:.1f} mm"


def reducing_elbow_source(b, name, big, small, degrees, listed, source, standard, pipes, notes):
    """(``dimensions`` record, standard?) of the reducing elbow ``name`` from ``big`` to
    ``small`` turning ``degrees``: ASME B16.9 makes reducing elbows as 90 degree long-radius
    elbows of listed pairs only (``catalogs/<fittings>-elbows.toml``, ``listed`` its A, False
    for a pair not made, None for no verdict). Any other is built as before, said to be
    non-standard, with a note on ``pipes`` and in ``notes``."""
    sizes = f"{size_text(big)} to {size_text(small)}"
    if abs(degrees - 90.0) > ELBOW45_WINDOW_DEG:
        text = (
            f"the elbow {name} joins {sizes} turning {degrees:.0f} degrees: ASME B16.9 makes "
            "reducing elbows as 90 degree long-radius elbows only; built as a bend of the "
            f"{size_text(big)} elbow's dimensions, each end its pipe's size, a fitting the standard "
            "does not make (an elbow and a reducer, or check the sizes)"
        )
        if standard:
            source = f"{source}, reducing elbow at {degrees:.0f} degrees (non-standard)"
    elif listed is False:
        made = reducing_elbow_ends(big.dims.source).get(big.nominal, {})
        ends = sorted(made, key=nps_order, reverse=True)
        text = (
            f"no NPS {big.nominal} x {small.nominal} reducing elbow in {big.dims.source} (NPS "
            f"{big.nominal} reduces to {', '.join(ends)} only): built as a 90 degree elbow of "
            f"the {size_text(big)} radius, each end its pipe's size, a fitting the standard does not "
            "make (an elbow and a reducer, or check the sizes)"
        )
        source = f"{source} radius; no such reducing elbow (non-standard)"
    else:
        return source, standard
    notes.append(text)
    b.note(pipes, text)
    return source, False
