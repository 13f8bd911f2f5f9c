"""Plane geometry: regions of a plane in 2-D coordinates, one module a job.

- :mod:`.predicates`: tests on loops and points (signed areas, convexity,
  star-shaped and simple loops that need no union, points in polygons);
- :mod:`.budget`: what a union would cost Clipper2, counted before it runs;
- :mod:`.nesting`: a region's loops grouped into parts ``[outer, hole, ...]``;
- :mod:`.union`: the one 2-D union, :func:`unite`, which checks the budget
  before every Clipper2 call, and the region operations after it
  (:func:`intersect`, :func:`subtract`, :func:`add`);
- :mod:`.triangulation`: parts, polygons and loops cut into triangles.

Each module imports only those above it in this list. The names of all five
are gathered here, so a caller writes ``from shadowgeo import plane2d`` and
``plane2d.unite(loops)``. The package is the library's inside, not its public
API (that is ``shadowgeo.__all__``).
"""

from __future__ import annotations

from .budget import FEWEST_CROSSING_EDGES, crossings_estimate, sweep_bound, sweep_work
from .nesting import FlatParts, components, nest, nest_flat, parts_area, region_loops
from .predicates import (
    is_convex,
    loop_means,
    many_reflex,
    points_in_parts,
    signed_areas,
    star_shaped_flat,
    swept_triangles,
    whole_loop,
)
from .triangulation import (
    STRAIGHT_SLACK,
    fan,
    polygon_triangles,
    polygons_triangles,
    star_triangles,
    triangulate_parts,
)
from .union import (
    ARRANGED_LOOPS,
    Form,
    Rule,
    add,
    holds_box,
    intersect,
    local_scale,
    subtract,
    triangles_region,
    unite,
    without_copies,
)

__all__ = [
    "ARRANGED_LOOPS",
    "FEWEST_CROSSING_EDGES",
    "STRAIGHT_SLACK",
    "FlatParts",
    "Form",
    "Rule",
    "add",
    "components",
    "crossings_estimate",
    "fan",
    "holds_box",
    "intersect",
    "is_convex",
    "local_scale",
    "loop_means",
    "many_reflex",
    "nest",
    "nest_flat",
    "parts_area",
    "points_in_parts",
    "polygon_triangles",
    "polygons_triangles",
    "region_loops",
    "signed_areas",
    "star_shaped_flat",
    "star_triangles",
    "subtract",
    "swept_triangles",
    "sweep_bound",
    "sweep_work",
    "triangles_region",
    "triangulate_parts",
    "unite",
    "whole_loop",
    "without_copies",
]
