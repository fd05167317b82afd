"""Triangle meshes of the solids, tessellated once and shared by the mesh-based exporters.

The kernel's incremental mesher (``BRepMesh_IncrementalMesh``) triangulates each B-rep face;
the nodes are gathered into numpy arrays. The kernel is imported only when :func:`tessellate`
runs, so :class:`Mesh` and :mod:`asbuilt.cad.meshgen` stay plain numpy. Vertices are kept per B-rep face (not merged across
edges) so that vertex normals, averaged from the triangles of one face only, stay smooth on
curved faces and sharp at edges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Mesh", "tessellate", "vertex_normals", "LINEAR_DEFLECTION", "ANGULAR_DEFLECTION"]

#: Largest distance (metres) between a triangle and the true surface: 0.5 mm, well below the
#: fits' uncertainty (a few mm), so the mesh does not add visible error.
LINEAR_DEFLECTION = 5e-4
#: Largest angle (radians) between neighbouring triangles' normals on a curved face: 0.25 rad
#: gives at least 26 facets around a pipe, whose area is then within 1% of the circle's.
ANGULAR_DEFLECTION = 0.25


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh.

    Attributes
    ----------
    vertices : ndarray, shape (n, 3), float64, metres
    faces : ndarray, shape (m, 3), int64
        Counter-clockwise seen from outside.
    normals : ndarray, shape (n, 3), float64
        Unit vertex normals.
    """

    vertices: np.ndarray
    faces: np.ndarray
    normals: np.ndarray

    @property
    def volume(self) -> float:
        """Enclosed volume, cubic metres (divergence theorem over the triangles).

        Summed about the vertices' mean: about the scan's origin, a mesh at survey coordinates
        (5,000 km) sums products of 1e6 m that cancel to noise larger than the volume itself.
        """
        vertices = (
            self.vertices - self.vertices.mean(axis=0) if len(self.vertices) else self.vertices
        )
        tri = vertices[self.faces]
        return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6)

    def merged(self, decimals: int = 9) -> tuple[np.ndarray, np.ndarray]:
        """Vertices merged where they coincide (to ``decimals`` metres digits) and the re-indexed
        faces: ``(vertices (k, 3) m, faces (m, 3))``, a closed surface for a closed solid."""
        keys = np.round(self.vertices, decimals)
        unique, inverse = np.unique(keys, axis=0, return_inverse=True)
        return unique, inverse.reshape(-1)[self.faces]


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unit vertex normals, shape (n, 3): the area-weighted mean of the adjacent triangles'
    normals (vertices (n, 3) metres, faces (m, 3) counter-clockwise from outside)."""
    tri = vertices[faces]
    weighted = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])  # area-weighted
    normals = np.zeros_like(vertices)
    for corner in range(3):
        np.add.at(normals, faces[:, corner], weighted)
    norms = np.linalg.norm(normals, axis=1)
    bad = norms <= 1e-300
    normals[bad] = (0.0, 0.0, 1.0)
    norms[bad] = 1.0
    return normals / norms[:, None]


def tessellate(
    shape,
    linear: float = LINEAR_DEFLECTION,
    angular: float = ANGULAR_DEFLECTION,
) -> Mesh:
    """Triangulate a solid (or any shape with faces).

    Parameters
    ----------
    shape : cadquery.Shape
        In metres.
    linear : float, metres
        Largest chord deviation from the surface.
    angular : float, radians
        Largest angle between neighbouring facets.

    Returns
    -------
    Mesh
        Vertices in metres, per B-rep face (see the module docstring).
    """
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    BRepMesh_IncrementalMesh(shape.wrapped, linear, False, angular, True)
    vertex_blocks: list[np.ndarray] = []
    face_blocks: list[np.ndarray] = []
    offset = 0
    explorer = TopExp_Explorer(shape.wrapped, TopAbs_FACE)
    while explorer.More():
        face = TopoDS.Face_s(explorer.Current())
        explorer.Next()
        loc = TopLoc_Location()
        poly = BRep_Tool.Triangulation_s(face, loc)
        if poly is None:
            continue
        nodes = np.array(
            [poly.Node(i).Coord() for i in range(1, poly.NbNodes() + 1)], dtype=np.float64
        )
        if not loc.IsIdentity():
            trsf = loc.Transformation()
            matrix = np.array([[trsf.Value(r, c) for c in (1, 2, 3, 4)] for r in (1, 2, 3)])
            nodes = nodes @ matrix[:, :3].T + matrix[:, 3]
        tris = (
            np.array(
                [poly.Triangle(i).Get() for i in range(1, poly.NbTriangles() + 1)], dtype=np.int64
            )
            - 1
        )
        if face.Orientation() == TopAbs_REVERSED:
            tris = tris[:, [0, 2, 1]]
        vertex_blocks.append(nodes)
        face_blocks.append(tris + offset)
        offset += len(nodes)
    if not vertex_blocks:
        empty = np.zeros((0, 3))
        return Mesh(empty, np.zeros((0, 3), dtype=np.int64), empty)
    vertices = np.concatenate(vertex_blocks)
    faces = np.concatenate(face_blocks)
    return Mesh(vertices, faces, vertex_normals(vertices, faces))
