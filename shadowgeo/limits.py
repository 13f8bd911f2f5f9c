"""What shadowgeo accepts: the range of numbers its geometry carries, and the
budgets of its readers. Every limit is stated here, once.

Coordinate range
----------------
The shadow formulas multiply coordinates: a face normal is a product of two
edge vectors, the facing test and the winding number products of three
lengths, the shadow matrix applied to a point a product of four. Float64
holds magnitudes from about 2.2e-308 to 1.8e308, so a product of four numbers
each within ``[1e-75, 1e75]`` (with room for the constant factors) neither
overflows nor underflows to zero:

``LARGEST_COORDINATE = 1e75``
    The largest absolute coordinate, light position, plane offset, finite
    light radius, primitive size or number in a scene file.
``SMALLEST_LENGTH = 1e-75``
    The smallest scene size (bounding-box diagonal) and primitive size.

That is 150 orders of magnitude; a scene in metres from a proton (1e-15) to
the observable universe (9e26) fits with room to spare. Past either end the
geometry raises :class:`~shadowgeo.GeometryError` and the readers
:class:`~shadowgeo.SceneError`, naming the value: there is no result that
float64 could be trusted to compute. A light radius may also be ``inf`` (no
limit).

Reader budgets
--------------
A hostile file stops at a budget with a ``SceneError`` naming it, in bounded
time and memory (the two segment caps are not errors: a curve simply gets no
finer). Only the triangle budget has an option that raises it (below); the
others sit far above any real scene (edit the constant to go further);
``--tolerance`` only moves the chord within the segment caps.

=====================  ==============  =============================================
budget                 value           where it is enforced
=====================  ==============  =============================================
document size          512 MiB         X3D after inflating ``.x3dz`` (an inflation
                                       bomb stops there)
XML depth              256 elements    X3D, checked on the parsed tree (libxml2
                                       stops at 2,048 while parsing)
nesting                256 groups      grouping nodes inside one another as the
                                       scene is walked, through DEF/USE,
                                       prototypes and Inline
XML text or attribute  document size   X3D: one attribute may fill the document
                                       budget (a 1.3M-triangle mesh is ~45 MB);
                                       libxml2's 10 MB limit for untrusted input
                                       stays for documents in an encoding other
                                       than UTF-8 / ASCII / ISO-8859 / windows-125x
USD layer check        512 MiB + 64 B      each ``.usda`` layer over 64 KiB and each
                       per byte; 10 s  ``.usdc`` crate (every value unpacked), read
                       + 1 s per MB    first in a child process held to this memory
                                       and CPU time (a malformed text layer can take
                                       gigabytes; a corrupt crate can abort usd-core)
entity declarations    none            X3D: ``<!ENTITY`` in the bytes is refused
                                       before libxml2 parses anything
nodes                  2,000,000       X3D nodes after DEF/USE, Inline and PROTO
                                       expansion, counted over every copy
node visits            500,000         X3D grouping nodes and Shapes the reader
                                       walks, every copy counted, estimated
                                       before the walk (about 10 us each)
scene memory           2 GB            the triangles of a scene x 400 bytes
                       (5M triangles)  (BYTES_PER_TRIANGLE), estimated before they
                                       are built: X3D through DEF/USE, PROTO and
                                       Inline (shadowgeo.io.x3d.budget), glTF
                                       meshes through their nodes, USD meshes
                                       through their instances
PROTO expansions       10,000          ProtoInstance copies per document
lights                 10,000          lights of a scene as read, every copy
                                       counted (X3D, glTF, USD)
casting lights         100             lights whose shadows ``add_shadows`` bakes
                                       when none is named: the first ones cast,
                                       with a note (``--light NAME`` chooses)
Inline depth           16              nested X3D Inlines
Inline instances       10,000          X3D Inlines read, every copy counted
                                       (through DEF/USE and Inlines inside
                                       Inlines), each checked before it is read
Extrusion              2,500,000       vertices (spine points x cross-section
                                       points) of one Extrusion, before it is
                                       built: its side alone fills the default
                                       triangle budget (about 580 MB to build)
sphere segments        2,048           segments around one tessellated Sphere
                                       (a finer chord is not met; the reader notes
                                       it)
curve segments         65,536          segments of any other tessellated curve
outline crossings      2,000,000       edge crossings among the 2-D loops one shadow
                                       unites (estimated from fixed samples of edge
                                       pairs and edges): a soup of overlapping
                                       triangles, or an Extrusion whose spine folds
                                       over itself, is refused in a fraction of a
                                       second rather than united in minutes
union sweep            500,000,000     steps of Clipper2's sweep placing one union's
                                       edges (per scanline, edges beginning there
                                       times edges spanning it): a soup of copies of
                                       one template, its corners on a few lines, is
                                       refused rather than united in minutes with
                                       no crossing at all
polygon corners        20,000          corners of one polygon triangulated in its
                                       plane (an X3D face that is not convex, a
                                       CityJSON ring with its holes): the ear
                                       clipper's worst case grows with their
                                       square (a face retracing its corners
                                       10,000 times: 40,000 corners, over 30 s)
template points        5,000,000       CityJSON: points made by placing geometry
                                       templates (GeometryInstance), counted over
                                       every instance as they are read (a small
                                       file can instance a big template millions
                                       of times)
surface pairs          5,000,000       (receiving face, caster triangle) pairs that
                                       overlap as seen from a light in
                                       ``shadow_on_surface``; past it, an error
                                       before the pairs fill memory
DEM raster             1,000,000,000   a GeoTIFF's width x height, checked from its
                       cells           header before any pixel is read
                                       (``shadowgeo.io.dem``); the window read is
                                       averaged down to ``DEM_CELLS`` (40,000)
=====================  ==============  =============================================

Triangles: a scene of more than ``MAX_TRIANGLES`` (5,000,000) after
tessellation and instancing is refused by :func:`shadowgeo.load` (its
``max_triangles`` argument, or ``convert --max-triangles N``, raises the
budget for a trusted file): time and memory grow with them. Duplicate and
zero-area triangles, and copied outline loops, cost nothing in the shadow's
2-D union (:func:`shadowgeo.project_shadow` and :func:`~shadowgeo.plane2d.union.unite`
drop them first), and shapes that repeat another's geometry exactly cast once.
What the union costs grows with the crossings of its edges (Clipper2's sweep
does work for each one, and more than linearly in practice), so that is what
the outline budget counts: a ``GeometryError`` from the shadow computation, which
:func:`shadowgeo.add_shadows` reports as a note naming the shape that does not
cast.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .errors import GeometryError, SceneError

if TYPE_CHECKING:
    from .lights import Light
    from .plane import Plane
    from .topology import Caster

__all__ = [
    "ANGLE_SLACK",
    "CONVEX_TURN",
    "CROSSING_RESOLUTION",
    "DEM_CELLS",
    "FLOAT32_AGREEMENT",
    "FRAME_ROUNDING",
    "LARGEST_COORDINATE",
    "MATRIX_ROUNDING",
    "MAX_BODY_FACES",
    "MAX_CASTING_LIGHTS",
    "MAX_CURVE_SEGMENTS",
    "MAX_DEM_RASTER_CELLS",
    "MAX_DOCUMENT_BYTES",
    "MAX_EXTRUSION_POINTS",
    "MAX_INLINE_DEPTH",
    "MAX_INLINE_INSTANCES",
    "MAX_LIGHTS",
    "MAX_NESTING",
    "MAX_NODES",
    "MAX_PIECE_PAIRS",
    "MAX_POLYGON_CORNERS",
    "MAX_PROTO_EXPANSIONS",
    "MAX_SPHERE_SEGMENTS",
    "MAX_SURFACE_FACES",
    "MAX_SURFACE_PAIRS",
    "MAX_TEMPLATE_POINTS",
    "MAX_TRIANGLES",
    "MAX_UNION_CROSSINGS",
    "MAX_UNION_SWEEP",
    "MAX_XML_DEPTH",
    "ORIENTATION_ERROR",
    "PRODUCT_ROUNDING",
    "PRODUCT_SLACK",
    "RELATIVE_ROUNDING",
    "SHORTEST_DIRECTION",
    "SINGULAR_SHARE",
    "SMALLEST_DRAWN_SIZE",
    "SMALLEST_LENGTH",
    "TINY",
    "TRS_RELATIVE",
    "USD_TEXT_BYTES_PER_SECOND",
    "USD_TEXT_CHECK_BYTES",
    "USD_TEXT_MEMORY",
    "USD_TEXT_MEMORY_PER_BYTE",
    "USD_TEXT_SECONDS",
    "check_coordinates",
    "check_geometry",
    "check_length",
    "check_light",
    "check_lights",
    "check_triangles",
    "lights_message",
]

LARGEST_COORDINATE = 1e75
SMALLEST_LENGTH = 1e-75

MAX_DOCUMENT_BYTES = 512 * 1024 * 1024
MAX_XML_DEPTH = 256
# Grouping nodes one inside another as the X3D reader walks the scene, counted
# through DEF/USE, prototypes and Inline (the reader raises Python's recursion
# limit to hold this many levels above its caller's stack).
MAX_NESTING = MAX_XML_DEPTH
MAX_NODES = 2_000_000
# Grouping nodes and Shapes the X3D reader walks one by one, every copy
# counted, estimated before the walk (shadowgeo.io.x3d.budget): about 10 us
# each even when they hold nothing, so 5 CPU-s at most. A 1.1 KB chain of
# empty Transforms, each USEing the one before ten times, asked for 1.1M
# (under MAX_NODES) and took 19-36 CPU-s.
MAX_VISITS = 500_000
# Prototype copies a scene makes. A file that writes more ProtoInstances than
# this outside its declarations is refused before the walk (10,001 copies made
# one by one took 16 CPU-s to reach the count); copies inside copies are
# counted as the walk makes them.
MAX_PROTO_EXPANSIONS = 10_000
# Lights of a scene as read: each is a node of the output, and a fuzzed file
# that copies one 30,000 times took 11 CPU-s to read and write. An X3D file
# that writes more light nodes than this outside its declarations is refused
# before the walk.
MAX_LIGHTS = 10_000
# Lights whose shadows add_shadows bakes unless the caller names them: each
# is a shadow pass over every caster and receiver.
MAX_CASTING_LIGHTS = 100
MAX_INLINE_DEPTH = 16
# X3D Inline instances read, every copy counted: each is a document walked
# anew (~0.2 ms even for a small file), and 16 files of 250 bytes that each
# inline the next ten times ask for 10^15; counted before each is read.
MAX_INLINE_INSTANCES = 10_000
# Vertices one Extrusion may make, checked before it is built (about 230
# bytes each while it is): its side alone, about two triangles a vertex, then
# fills the default triangle budget, which refused 18M vertices only after
# 3.8 GB had been spent making them.
MAX_EXTRUSION_POINTS = 2_500_000
MAX_SPHERE_SEGMENTS = 2048
MAX_CURVE_SEGMENTS = 1 << 16
# Edge crossings one 2-D union may have to resolve (about half a second of
# Clipper2 on one core); estimated by plane2d.crossings_estimate.
MAX_UNION_CROSSINGS = 2_000_000
# Steps of Clipper2's sweep placing edges among the active ones, in one 2-D
# union, counted by plane2d.sweep_work: 2 to 10 ns each (a template soup on
# 200 scanlines, 2.7e9 steps: 5.5 s; a fan of 32,768 thin triangles round one
# point, 3.2e9: 33 s), so about 1 to 5 CPU s at the budget. The real scenes
# (the corpus, the goldens, benchmarks/bench_buildings.py's 1.2M-edge union)
# need at most 3e7.
MAX_UNION_SWEEP = 500_000_000
# Corners of one polygon triangulated in its plane (plane2d.polygon_triangles):
# manifold3d's ear clipper costs about 15 ns x corners^2 at worst (a face
# retracing its corners: 8,006 corners 0.93 s, 40,006 over 30 s), so about 6 s
# here; a simple polygon of 20,000 corners takes 0.1 s.
MAX_POLYGON_CORNERS = 20_000
# (receiving face, caster triangle) pairs whose images from a light overlap,
# in shadow_on_surface: each pair is clipped, so their count is its work.
MAX_SURFACE_PAIRS = 5_000_000
# Faces that receive through shadow_on_surface in add_shadows (beyond the planar
# receivers), per light; a bigger scene bakes planar shadows only, with a note.
# At this size (benchmarks/bench_surface.py's terrain at 100,000 faces under a
# sphere) a point light costs about 0.2 s, a low sun with long shadows about 3 s.
MAX_SURFACE_FACES = 100_000
# Faces of one closed body tested for being convex (shadowgeo.bodies): the test
# measures every vertex against every face plane of its body (a box: 12 x 8),
# so a larger body keeps its triangles rather than cost faces x vertices.
MAX_BODY_FACES = 512
# Pairs of convex pieces on one face whose overlap the compiled union of
# shadowed_fractions measures (its cost: about 0.3 us a pair of hexagons, so
# some 6 s here); beyond it the faces' shares come from the 2-D union.
MAX_PIECE_PAIRS = 20_000_000
# A DEM (shadowgeo.io.dem): a raster whose width x height passes this is
# refused from its header, before a pixel is read (a hostile header can claim
# 2^31 x 2^31 cells in a few bytes); the window read around the study is then
# averaged down to at most DEM_CELLS cells (two terrain triangles each: 80,000
# triangles, the size of a city district's buildings, received and cast at
# every sun sample).
MAX_DEM_RASTER_CELLS = 1_000_000_000
DEM_CELLS = 40_000
# A USD text layer is first parsed in a child process within this address
# space (on top of what the process maps already) and CPU time (see
# shadowgeo.io.usd_text): a malformed .usda can make usd-core's parser take
# gigabytes.
USD_TEXT_MEMORY = 512 * 1024 * 1024
USD_TEXT_MEMORY_PER_BYTE = 64
USD_TEXT_SECONDS = 10
USD_TEXT_BYTES_PER_SECOND = 1_000_000
# A text layer of at most this many bytes is parsed in the caller, without the
# child process (which costs about 0.35 s to start): the malformed layer found
# by fuzzing was 725 KB, and the campaign's mutants of small layers, parsed in
# the fuzzer's own 20 CPU-s / 1.5 GB budget, never came near it.
USD_TEXT_CHECK_BYTES = 64 * 1024
# Points a CityJSON file's GeometryInstances make from their templates, all
# instances counted as they are read: the triangle budget is checked only
# after reading, too late for an expansion bomb.
MAX_TEMPLATE_POINTS = 5_000_000
# Triangles of a scene as read (after tessellation and instancing): what a
# conversion's time and memory grow with. At this size a conversion takes
# about 15 CPU seconds and 2 GB; load(..., max_triangles=N) or
# ``convert --max-triangles N`` raises it for a trusted file.
MAX_TRIANGLES = 5_000_000
# The peak memory of one scene's conversion, and what it is made of: a scene's
# triangles each take about this many bytes at the peak (read, shadows added,
# written; measured by benchmarks/bench_memory.py). The triangle budget is the
# memory budget in triangles; the readers estimate a scene's triangles before
# they build them (X3D: through DEF/USE, prototypes and Inline; glTF: meshes
# through their nodes; USD: meshes through their instances) and refuse,
# naming the node, what would pass it.
BYTES_PER_TRIANGLE = 400
MEMORY_BUDGET = MAX_TRIANGLES * BYTES_PER_TRIANGLE


def check_expansion(
    triangles: int,
    path: str,
    node: str | None,
    line: int | None,
    limit: int | None = None,
    *,
    through: str = "DEF/USE, prototypes or Inline",
) -> None:
    """Raise :class:`SceneError` for ``node`` of ``path`` when what it expands
    to, an estimated ``triangles``, would pass the memory budget (``limit``
    triangles, default :data:`MAX_TRIANGLES`), before it is built.

    Examples
    --------
    >>> check_expansion(12, "nest.x3d", "Transform DEF='L0'", 2)
    >>> check_expansion(12 * 10**10, "nest.x3d", "Transform DEF='L10'", 12)
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    shadowgeo.errors.SceneError: nest.x3d line 12, Transform DEF='L10': ... 1.2e+11 triangles ...
    """
    limit = MAX_TRIANGLES if limit is None else int(limit)
    if triangles > limit:
        raise SceneError(
            f"with this the scene expands (through {through}) to about "
            f"{triangles:.2g} "
            f"triangles (~{triangles * BYTES_PER_TRIANGLE / 1e9:.3g} GB at "
            f"{BYTES_PER_TRIANGLE} bytes each), more than the budget of {limit:,} "
            f"(~{limit * BYTES_PER_TRIANGLE / 1e9:.3g} GB; shadowgeo.limits.MAX_TRIANGLES; "
            "--max-triangles N raises it for a trusted file); refused before it is built",
            path=path,
            line=line,
            node=node,
        )


def check_triangles(count: int, path: str, limit: int | None = None) -> None:
    """Raise :class:`SceneError` for ``path`` when a scene of ``count``
    triangles exceeds ``limit`` (default :data:`MAX_TRIANGLES`).

    Examples
    --------
    >>> check_triangles(12, "box.x3d")
    >>> check_triangles(12, "box.x3d", limit=10)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    shadowgeo.errors.SceneError: box.x3d: 12 triangles ..., more than the budget of 10 ...
    """
    limit = MAX_TRIANGLES if limit is None else int(limit)
    if count > limit:
        raise SceneError(
            f"{count:,} triangles (after tessellation and instancing), more than the budget "
            f"of {limit:,} (shadowgeo.limits.MAX_TRIANGLES; --max-triangles N raises it for "
            "a trusted file)",
            path=path,
        )


def lights_message(count: int) -> str:
    """Why a scene with ``count`` lights (more than :data:`MAX_LIGHTS`) is refused."""
    return f"more than {MAX_LIGHTS:,} lights ({count:,} so far; shadowgeo.limits.MAX_LIGHTS)"


def check_lights(count: int, path: str) -> None:
    """Raise :class:`SceneError` for ``path`` when a scene has ``count``
    lights, more than :data:`MAX_LIGHTS`.

    >>> check_lights(MAX_LIGHTS, "city.glb")
    >>> check_lights(MAX_LIGHTS + 1, "city.glb")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    shadowgeo.errors.SceneError: city.glb: more than 10,000 lights (10,001 so far; ...)
    """
    if count > MAX_LIGHTS:
        raise SceneError(lights_message(count), path=path)


def check_coordinates(points: ArrayLike, what: str) -> None:
    """Raise :class:`GeometryError` unless every value of ``points`` is finite
    and within ``+-LARGEST_COORDINATE``; the message names ``what``, the
    offending point and its value.

    Examples
    --------
    >>> check_coordinates([[0, 1, 2]], "caster")
    >>> check_coordinates([[0, 1e80, 2]], "caster")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    shadowgeo.errors.GeometryError: caster point 0 has coordinate 1e+80, outside ... +-1e+75
    """
    values = np.asarray(points, dtype=np.float64)
    if values.size == 0:
        return
    if values.max() <= LARGEST_COORDINATE and values.min() >= -LARGEST_COORDINATE:
        return  # every value finite and in range (NaN fails both comparisons)
    flat = values.reshape(len(values), -1) if values.ndim > 1 else values.reshape(-1, 1)
    bad = ~np.all(np.isfinite(flat) & (np.abs(flat) <= LARGEST_COORDINATE), axis=1)
    if not bad.any():
        return
    index = int(np.flatnonzero(bad)[0])
    row = flat[index]
    value = float(
        row[np.argmax(~np.isfinite(row) | (np.abs(np.nan_to_num(row)) > LARGEST_COORDINATE))]
    )
    label = f"{what} point {index}" if values.ndim > 1 else what
    if not math.isfinite(value):
        raise GeometryError(f"{label} has a coordinate that is not finite ({value!r})")
    raise GeometryError(
        f"{label} has coordinate {value!r}, outside the supported range +-{LARGEST_COORDINATE:g}"
    )


def check_length(value: float, what: str, *, infinite: bool = False) -> float:
    """``value`` as a float if it is a length shadowgeo can carry: finite (or
    ``inf`` when ``infinite``), > 0, and within
    ``[SMALLEST_LENGTH, LARGEST_COORDINATE]``; else :class:`GeometryError`
    naming ``what`` and the value.

    Examples
    --------
    >>> check_length(2, "Sphere radius")
    2.0
    >>> check_length(1e-80, "Sphere radius")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    shadowgeo.errors.GeometryError: Sphere radius 1e-80 is below the smallest ... 1e-75
    """
    value = float(value)
    if infinite and value == math.inf:
        return value
    if not (value > 0 and math.isfinite(value)):
        raise GeometryError(f"{what} must be finite and > 0, got {value!r}")
    if value < SMALLEST_LENGTH:
        raise GeometryError(
            f"{what} {value!r} is below the smallest supported length {SMALLEST_LENGTH:g}"
        )
    if value > LARGEST_COORDINATE:
        hint = " (use inf for no limit)" if infinite else ""
        raise GeometryError(
            f"{what} {value!r} is above the largest supported length {LARGEST_COORDINATE:g}{hint}"
        )
    return value


def check_light(light: Light, what: str = "light") -> None:
    """Raise :class:`GeometryError` when a light's position or finite radius
    is outside the supported range (a direction is a unit vector: always fine)."""
    position = getattr(light, "position", None)
    if position is not None:
        check_coordinates(position, f"{what} position")
    radius = getattr(light, "radius", math.inf)
    check_length(radius, f"{what} radius", infinite=True)


def check_geometry(caster: Caster, light: Light, plane: Plane | None = None) -> None:
    """Raise :class:`GeometryError` unless a caster's coordinates (a
    :class:`~shadowgeo.Caster`), a light's position and radius, and a
    plane's offset are all within the supported range: the check at the
    entry of every shadow computation."""
    if caster.n_faces:
        check_coordinates(caster.bounds, "caster bounds")
    check_light(light)
    if plane is not None:
        check_coordinates([plane.offset], "plane offset")


# -- Numeric guards ------------------------------------------------------------------
# Fixed numbers that keep float64 arithmetic from dividing by zero or from
# telling apart values that differ by rounding alone. Unlike the tolerances of
# shadowgeo.tolerance they do not scale with the scene: each is a share of the
# values it compares, a cosine, an angle, or says what else it guards. Every
# number below 1e-6 in shadowgeo lives here or in tolerance.py
# (tests/test_epsilons.py).

# Floor of a divisor (a box's extent, a squared length, a norm): a degenerate
# one divides to a large finite number, not inf or NaN. Far below any real
# divisor (SMALLEST_LENGTH squared is 1e-150), so it never changes one.
TINY = 1e-300
# Share of the values compared by which two results from the same inputs,
# reached along different float64 paths (a sum of many terms, a box grown or
# shrunk by rounding, a duration summed from steps), may differ and still
# agree: a few hundred roundings of 1.1e-16 each, with room.
RELATIVE_ROUNDING = 1e-9
# Share by which one product or difference of products (a cross product, a
# cosine or sine of unit vectors, a turn against its lengths) may be off.
PRODUCT_ROUNDING = 1e-12
# Entries of a transform, from a product of matrices or a singular value
# decomposition, compared with 0 or 1: within this the transform is plain
# (no projection, no rotation, unit scale); a few ulps of 1.
MATRIX_ROUNDING = 1e-15
# Coordinates of 2-D loops within +-polygons' MAX_COORDINATE: a product of two
# of their differences is off by this much relative (orientation.POINT_SLACK
# bounds the differences themselves).
PRODUCT_SLACK = 1e-13
# Rounding error bound of a 2-D orientation (a 2x2 determinant of coordinate
# differences) as a multiple of the squared extent of the points involved:
# Shewchuk's (3 + 16 eps) eps times the sum of the two products' magnitudes
# (each at most the extent squared) is 6.7e-16; ten times that for margin.
ORIENTATION_ERROR = 1e-14
# Rounding of a point turned into another frame, as a share of the largest
# coordinate (a few ulps; a thousand for margin).
FRAME_ROUNDING = 1e-13
# Crossing parameters along one edge closer than this are not ordered (the
# sort key edge + t resolves about 1e-11 at 60,000 edges; 64 ulps of the
# edge count where that is coarser).
CROSSING_RESOLUTION = 1e-9
# A corner that turns this far (radians) the wrong way still counts as straight.
CONVEX_TURN = 1e-12
# Singular values below this share of the largest count as zero when a
# least-squares direction is solved from a point's face normals (sheets).
SINGULAR_SHARE = 1e-10
# glTF node matrices whose TRS decomposition misses them by more than this
# (relative) are not TRS: glTF's validator rejects them, so they are baked
# into vertices.
TRS_RELATIVE = 1e-9
# A vector shorter than this (in the file's units) has no direction: an X3D
# Extrusion's spine step or cross-section axis.
SHORTEST_DIRECTION = 1e-12
# Radians by which a spot light's cut-off may fall short of a right angle
# and still light a whole half-space; and by which the turns of a loop may
# miss one full turn and still wind once.
ANGLE_SLACK = 1e-6
# Share by which a USD float attribute may differ from shadowgeo's exact
# double beside it and still be the same number (float32 keeps ~7 digits).
FLOAT32_AGREEMENT = 1e-6
# Floor of the drawn scene's diagonal in viz, for a scene of one point.
SMALLEST_DRAWN_SIZE = 1e-12
