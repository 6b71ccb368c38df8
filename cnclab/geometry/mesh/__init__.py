"""Triangle meshes for CAM: STL read/write, facet normals, incentres, nearest-facet lookup.

Modules by role (everything re-exported here): :mod:`~cnclab.geometry.mesh.core` (the mesh type and
per-facet geometry), :mod:`~cnclab.geometry.mesh.stl` (STL exchange), :mod:`~cnclab.geometry.mesh.repair`
(orientation repair), :mod:`~cnclab.geometry.mesh.locator` (nearest facet).

STL files are read by a strict reader of cnclab's own (binary recognised by its size, ASCII with
every solid, errors naming file and line or facet; see :func:`read_stl`) and written with numpy-stl.
All lengths are in mm. A :class:`TriMesh` holds the corner coordinates ``triangles`` (F, 3, 3) and unit
facet ``normals`` (F, 3).

Normals. The STL standard says the stored facet normal must agree with the counter-clockwise vertex
order (right-hand rule), but many exporters write zeros or stale normals. cnclab therefore **always
uses the normal recomputed from the vertex order**; the stored normals are only compared with it,
and the number of stored normals that were missing (zero) or inconsistent (angle > 1 deg, or
opposite) is reported in ``TriMesh.info``. Winding: :func:`read_stl` re-orients facets consistently
(closed parts outward, open surfaces upward, :func:`orient_facets`) and reports the number flipped
(``info["reoriented_facets"]`` and an :class:`STLWarning`), so a file wound clockwise does not change
which facets count as the machined surface. ``read_stl(..., orient_up=True)`` additionally flips
facets whose recomputed normal points downwards (N_z < 0) -- useful for open height-field surfaces
written with mixed winding; closed solids should keep the default ``False``.

Nearest facet. Mgherony (2024, Sec. 7.2.3) assigns each cutter location the facet whose "incentre"
(which the thesis computes as the *average of the three corners*, i.e. the centroid) is nearest.
:class:`FacetLocator` does this with a KD-tree (``nearest_centroid``), and also offers the exact
nearest facet in Euclidean distance (``nearest_facet``) and the true incentre (``facet_incentres``).
"""
from __future__ import annotations

from .core import (COORD_LIMIT_MM, STLError, TriMesh, facet_areas, facet_centroids, facet_incentres, facet_normals,
                   inclination_angles, machined_surface_mask)
from .locator import FacetLocator, closest_point_on_triangles
from .repair import orient_facets
from .stl import STLWarning, read_stl, write_stl

__all__ = ["TriMesh", "read_stl", "write_stl", "facet_normals", "facet_centroids", "facet_incentres",
           "facet_areas", "machined_surface_mask", "FacetLocator", "closest_point_on_triangles",
           "inclination_angles", "orient_facets", "STLError", "STLWarning", "COORD_LIMIT_MM"]
