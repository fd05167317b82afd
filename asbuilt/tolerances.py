"""One explicit, frozen set of numerical tolerances, passed down from the caller.

Every field says why it has its value (in the spirit of trimesh's ``constants.py``, without a
mutable global): change one with :func:`dataclasses.replace` and pass the new object down.
All lengths are metres, all angles degrees.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

__all__ = ["Tolerances", "DEFAULT_TOLERANCES", "MIN_POINTS"]


def _why(default, reason: str):
    return field(default=default, metadata={"reason": reason})


#: Fewest points that determine each kind at all (a fit below this is impossible, not just weak).
#: cylinder: 5 parameters + 1 redundant; cuboid: 3 faces need 3+2+1 = 6 and a size; the paper's
#: accuracy needs far more (see ``Tolerances.recommended_points_*``).
MIN_POINTS = {"plane": 3, "sphere": 4, "cylinder": 6, "cuboid": 7, "hull": 4, "auto": 7}


@dataclass(frozen=True)
class Tolerances:
    """Numerical tolerances for fitting and merging. All lengths in metres, angles in degrees."""

    outlier_cutoff_sigma: float = _why(
        3.0,
        "A residual beyond 3 robust sigmas is an outlier: for Gaussian range noise that rejects "
        "0.27% of good shots, while an edge-grazing shot that hit the wall behind is usually "
        "many centimetres (tens of sigmas) off.",
    )
    max_outlier_fraction: float = _why(
        0.45,
        "Robust estimators used here break down near 50% contamination; above 45% rejected the fit "
        "is not trusted and the object is reported instead of silently fitted to the background.",
    )
    sigma_floor: float = _why(
        1e-4,
        "0.1 mm: the smallest noise level a hand-held/pan-tilt range finder can claim; keeps "
        "robust scales finite on synthetic noise-free data.",
    )
    min_noise_dof: int = _why(
        5,
        "Residual degrees of freedom (inliers less parameters) a noise level estimated from the "
        "residuals needs: with fewer, the estimate scatters by a factor of two or more (a "
        "chi-square with 1-4 degrees of freedom), so a 3-sigma outlier test on it rejects good "
        "shots and standard errors scaled by it claim precision the points cannot give.",
    )
    prior_range_sigma: float = _why(
        0.002,
        "2 mm: the range noise assumed for the degrees of freedom a scan without a sensor sigma "
        "lacks (below min_noise_dof); typical of the inexpensive laser range finders asbuilt "
        "targets (1-3 mm), and the benchmark sensor's.",
    )
    normal_neighbours: int = _why(
        6,
        "Neighbours used for a local surface normal: the paper uses 2 (three-point sets); 6 "
        "averages range noise on a 20-40 point raster while staying on one face.",
    )
    face_angle_deg: float = _why(
        20.0,
        "Local normals within 20 degrees are the same cuboid face: a sparse raster's normals scatter "
        "by ~5-10 degrees, and adjacent faces of a cuboid are 90 degrees apart.",
    )
    recommended_points_cylinder: int = _why(
        20, "The paper's minimum for 1-5% cylinder error (Kwon et al., experimental results)."
    )
    recommended_points_cuboid: int = _why(
        30, "The paper's minimum for location, orientation and size of cuboids."
    )
    angle_snap_deg: float = _why(
        2.0,
        "Orientation regularisation (GlobFit, Li et al. 2011): axes within 2 degrees of parallel, "
        "perpendicular, vertical or horizontal are made exact; sparse fits are good to ~0.5 degree. "
        "An axis known worse (a short stub) is regularised up to angle_snap_max_deg.",
    )
    angle_snap_max_deg: float = _why(
        10.0,
        "An axis known worse than angle_snap_deg allows (3 standard errors above it: a 60 mm stub "
        "between two elbows, known to 3-4 degrees) is regularised within its 3 standard errors "
        "up to this (and never beyond intended_angle_deg): 45 and 90 degree elbows are what is "
        "built, and no scan of such a stub can tell 47 degrees from 45. Set it to "
        "angle_snap_deg for one cap on every axis.",
    )
    intended_angle_deg: float = _why(
        10.0,
        "Beyond 10 degrees off a regular direction an axis is taken as deliberately skewed, not "
        "misaligned, and no regularisation or misalignment finding applies.",
    )
    diameter_tolerance: float = _why(
        0.002,
        "2 mm: a fitted OD within max(3 standard errors, 2 mm) of a catalog OD may snap to it; "
        "from NPS 1/2 up the smallest gap between neighbouring steel pipe ODs is 5.4 mm (NPS 1/2 "
        "to 3/4); below it 3.4-4.2 mm (NPS 1/8 to 1/2), where an OD between two sizes is within "
        "2 mm of both and is reported ambiguous, not snapped.",
    )
    joint_distance: float = _why(
        0.15,
        "Pipes whose axes meet within 0.15 m of both pipe ends (plus the bend's centre-to-end) may "
        "be contiguous: sparse scans stop short of fittings by a shot spacing or so.",
    )
    plate_thickness: float = _why(
        0.010, "Planes become plates 10 mm thick so that CAD tools see a closed solid."
    )

    def reasons(self) -> dict[str, str]:
        """Each field's name mapped to the reason for its value."""
        return {f.name: f.metadata.get("reason", "") for f in fields(self)}


DEFAULT_TOLERANCES = Tolerances()
