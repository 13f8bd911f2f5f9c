"""shadow_on_surface against two independent references.

1. Per face, the textbook region: every other triangle of every caster
   (closed or not, front or back) clipped to the slab between the face's plane
   and the light, each corner sent through the light onto the plane by a
   ray/plane intersection, united with shapely and clipped to the face.
2. Rays: from random points of the light-facing faces to the light, a
   brute-force segment/triangle test against every caster triangle, compared
   with "inside the shadow mesh" (points within a tolerance of a shadow edge
   left out).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import trimesh
from reference import along_direction, basis, ray_plane, segment_hits_mesh

from shadowgeo import (
    DirectionalLight,
    GeometryError,
    Plane,
    PointLight,
    SpotLight,
    Tolerance,
    project_shadow,
    shadow_on_surface,
)

# -- scenes ---------------------------------------------------------------------------------


def grid(n, half, height=None, center=(0.0, 0.0)):
    """An n x n grid of squares (two triangles each) over [-half, half]^2 in x, z,
    facing +y, at the heights ``height(x, z)``."""
    xs = np.linspace(-half, half, n + 1) + center[0]
    zs = np.linspace(-half, half, n + 1) + center[1]
    x, z = np.meshgrid(xs, zs, indexing="ij")
    y = np.zeros_like(x) if height is None else height(x, z)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    index = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, d, c]), np.column_stack([a, c, b])])
    return trimesh.Trimesh(vertices, faces, process=False)


def heightfield(seed=3, n=12, half=4.0):
    rng = np.random.default_rng(seed)
    waves = rng.normal(size=(4, 4))

    def height(x, z):
        out = np.zeros_like(x)
        for i in range(4):
            out += (
                0.35
                * waves[i, 0]
                * np.sin(0.6 * (i + 1) * x + waves[i, 1])
                * np.cos(0.5 * (i + 1) * z + waves[i, 2])
            )
        return out

    return grid(n, half, height)


def sphere(center, radius, subdivisions=1):
    mesh = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    mesh.apply_translation(center)
    return mesh


def box(center, extents):
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation(center)
    return mesh


def stairs(steps=4, depth=1.0, rise=0.5, width=3.0):
    """An open staircase surface climbing along +x: treads facing +y, risers facing -x."""
    vertices, faces = [], []
    for i in range(steps):
        x0, x1, y0, y1 = i * depth, (i + 1) * depth, i * rise, (i + 1) * rise
        quads = [
            [[x0, y0, 0], [x0, y1, 0], [x0, y1, width], [x0, y0, width]],  # riser
            [[x0, y1, 0], [x1, y1, 0], [x1, y1, width], [x0, y1, width]],  # tread
        ]
        for quad in quads:
            base = len(vertices)
            vertices.extend(quad)
            faces.extend([[base, base + 2, base + 1], [base, base + 3, base + 2]])
    mesh = trimesh.Trimesh(vertices, faces, process=True)  # shared corners merged
    return mesh


# -- reference 1: per-face textbook regions ------------------------------------------------------


def face_frame(corners):
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    u, v = basis(normal)
    return normal, u, v


def to_face_2d(points, corners, u, v):
    relative = np.asarray(points) - corners[0]
    return np.column_stack([relative @ u, relative @ v])


def clip_between(polygon, heights_of, low, high):
    """The part of a 3-D convex polygon whose heights lie in [low, high]."""
    for sign, bound in ((1.0, low), (-1.0, -high)):
        if len(polygon) == 0:
            return polygon
        side = sign * heights_of(polygon) - bound
        out = []
        for i in range(len(polygon)):
            j = (i + 1) % len(polygon)
            if side[i] >= 0:
                out.append(polygon[i])
            if (side[i] >= 0) != (side[j] >= 0):
                t = side[i] / (side[i] - side[j])
                out.append(polygon[i] + t * (polygon[j] - polygon[i]))
        polygon = np.array(out).reshape(-1, 3)
    return polygon


def reference_region(corners, triangles, light, eps):
    """shapely region (face 2-D frame) hidden from ``light`` on the face."""
    normal, u, v = face_frame(corners)
    offset = -normal @ corners[0]

    def heights_of(points):
        return points @ normal + offset

    face = shapely.Polygon(to_face_2d(corners, corners, u, v))
    window = shapely.box(*(np.array(face.bounds) + [-1, -1, 1, 1]))
    if isinstance(light, DirectionalLight):
        high = math.inf
    else:
        high = heights_of(light.position[None])[0] * (1 - 1e-7)
    heights = triangles @ normal + offset
    # Strictly in front: some corner more than eps in front (not the face itself
    # or a coplanar neighbour); then all of it between the plane and the light.
    near = (heights.max(axis=1) > eps) & ~np.all(heights > high, axis=1)
    # A triangle wholly inside the slab has its image inside the hull of its
    # corners' images: skip those whose images miss the face's box.
    inside = np.all((heights >= 0) & (heights < high), axis=1)
    flat = triangles.reshape(-1, 3)
    if isinstance(light, DirectionalLight):
        images = along_direction(flat, light.direction, normal, offset)
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            images = ray_plane(flat, light.position, normal, offset)
    images = to_face_2d(images, corners, u, v).reshape(-1, 3, 2)
    low, top = np.array(face.bounds[:2]), np.array(face.bounds[2:])
    misses = np.any((images.min(axis=1) > top) | (images.max(axis=1) < low), axis=1)
    near &= ~(inside & misses)
    # Whole triangles in one vectorised call; the cut ones one by one.
    whole = near & inside
    pieces = list(shapely.polygons(images[whole]))
    for triangle in triangles[near & ~inside]:
        polygon = clip_between(triangle, heights_of, 0.0, high)
        if len(polygon) < 3:
            continue
        if isinstance(light, DirectionalLight):
            image = along_direction(polygon, light.direction, normal, offset)
        else:
            image = ray_plane(polygon, light.position, normal, offset)
        pieces.append(shapely.Polygon(to_face_2d(image, corners, u, v)).buffer(0))
    # Grazing light makes huge images: GEOS unites them wrongly unless cut first.
    pieces = shapely.intersection(np.array(pieces, dtype=object), window)
    pieces = [piece for piece in pieces if piece.area > 0]
    if not pieces:
        return shapely.Polygon()
    # Snap rounding on a fine grid keeps GEOS's overlay robust on slivers.
    return shapely.intersection(shapely.union_all(pieces, grid_size=1e-13), face, grid_size=1e-13)


def light_facing(corners, light, eps):
    normal, _, _ = face_frame(corners)
    if isinstance(light, DirectionalLight):
        return -normal @ light.direction > 1e-12
    return normal @ (light.position - corners[0]) > eps


def ours_on_face(shadow, face, corners):
    _, u, v = face_frame(corners)
    mask = shadow.face_index == face
    triangles = shadow.mesh.vertices[shadow.mesh.faces[mask]]
    polygons = [shapely.Polygon(to_face_2d(t, corners, u, v)) for t in triangles]
    return polygons


def check_against_textbook(shadow, surface, casters, light, scale):
    """Every light-facing face: ours equals the reference region; its triangles
    do not overlap; they lie in the face."""
    triangles = np.concatenate([c.vertices[c.faces] for c in casters])
    eps = 1e-9 * scale
    worst = 0.0
    for face, corners in enumerate(surface.vertices[surface.faces]):
        normal, u, v = face_frame(corners)
        polygons = ours_on_face(shadow, face, corners)
        if not light_facing(corners, light, eps):
            assert not polygons
            assert shadow.fraction[face] == 1.0
            continue
        expected = reference_region(corners, triangles, light, eps)
        ours = shapely.union_all(polygons) if polygons else shapely.Polygon()
        summed = sum(p.area for p in polygons)
        assert summed == pytest.approx(ours.area, abs=1e-12 * scale**2)  # no overlaps
        worst = max(worst, ours.symmetric_difference(expected).area)
        face_area = shapely.Polygon(to_face_2d(corners, corners, u, v)).area
        assert shadow.fraction[face] == pytest.approx(expected.area / face_area, abs=1e-7)
        mask = shadow.face_index == face
        points = shadow.mesh.vertices[shadow.mesh.faces[mask]].reshape(-1, 3)
        assert np.all(np.abs((points - corners[0]) @ normal) < 1e-9 * scale)
    assert worst < 1e-8 * scale**2


# -- reference 2: rays -------------------------------------------------------------------------


def check_rays(shadow, surface, casters, light, count, seed, scale):
    rng = np.random.default_rng(seed)
    corners = surface.vertices[surface.faces]
    eps = 1e-9 * scale
    facing = np.array([light_facing(c, light, eps) for c in corners])
    areas = surface.area_faces * facing
    faces = rng.choice(len(corners), size=count, p=areas / areas.sum())
    r1, r2 = rng.random(count), rng.random(count)
    flip = r1 + r2 > 1
    r1, r2 = np.where(flip, 1 - r1, r1), np.where(flip, 1 - r2, r2)
    tri = corners[faces]
    points = (
        tri[:, 0] + r1[:, None] * (tri[:, 1] - tri[:, 0]) + r2[:, None] * (tri[:, 2] - tri[:, 0])
    )
    inside, margin = np.zeros(count, bool), np.zeros(count)
    for face in np.unique(faces):
        mine = np.flatnonzero(faces == face)
        polygons = ours_on_face(shadow, face, corners[face])
        region = shapely.union_all(polygons) if polygons else shapely.Polygon()
        _, u, v = face_frame(corners[face])
        flat = shapely.points(to_face_2d(points[mine], corners[face], u, v))
        inside[mine] = shapely.covers(region, flat)
        margin[mine] = shapely.distance(region.boundary, flat) if polygons else np.inf
    clear = margin > 1e-6 * scale
    triangles = np.concatenate([c.vertices[c.faces] for c in casters])
    if isinstance(light, DirectionalLight):
        ends = points[clear] - 1e3 * scale * light.direction
    else:
        ends = np.broadcast_to(light.position, points[clear].shape)
    hits = segments_hit(points[clear], ends, triangles)
    # The vectorised test agrees with the shared brute-force one.
    sample = [
        segment_hits_mesh(p[None], e, triangles)[0]
        for p, e in zip(points[clear][:100], ends[:100], strict=True)
    ]
    np.testing.assert_array_equal(hits[:100], sample)
    assert clear.sum() > 0.98 * count
    assert hits.any() and not hits.all()
    disagree = np.flatnonzero(hits != inside[clear])
    assert len(disagree) == 0, f"{len(disagree)} of {clear.sum()} rays disagree"


def segments_hit(starts, ends, triangles, chunk=256):
    """(n,) bool: does each segment cross any triangle (Moller-Trumbore, every
    segment against every triangle, away from the segment's own ends)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = b - a, c - a
    out = np.zeros(len(starts), dtype=bool)
    for first in range(0, len(starts), chunk):
        start = starts[first : first + chunk, None, :]
        direction = ends[first : first + chunk, None, :] - start
        p = np.cross(direction, e2)
        det = np.einsum("tk,ntk->nt", e1, p)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = start - a
        bu = np.einsum("ntk,ntk->nt", s, p) * inv
        q = np.cross(s, e1)
        bv = np.einsum("ntk,ntk->nt", q, direction) * inv
        t = np.einsum("tk,ntk->nt", e2, q) * inv
        hit = ok & (bu >= 0) & (bv >= 0) & (bu + bv <= 1) & (t > 1e-12) & (t < 1 - 1e-12)
        out[first : first + chunk] = hit.any(axis=1)
    return out


def check_seamless(shadow, surface):
    """No crack: every boundary edge of the shadow mesh lying along a surface edge
    shared by two faces has no shadow just across it."""
    mesh = shadow.mesh
    if len(mesh.faces) == 0:
        return
    edges = mesh.edges_sorted
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    boundary = unique[counts == 1]
    corners = surface.vertices[surface.faces]
    adjacency = surface.face_adjacency
    edge_faces = {}
    for (f, g), shared in zip(adjacency, surface.face_adjacency_edges, strict=True):
        edge_faces[tuple(sorted(shared))] = (f, g)
    regions = {}

    def region(face):
        if face not in regions:
            polygons = ours_on_face(shadow, face, corners[face])
            regions[face] = shapely.union_all(polygons) if polygons else shapely.Polygon()
        return regions[face]

    starts = surface.vertices[np.array([key[0] for key in edge_faces])]
    ends = surface.vertices[np.array([key[1] for key in edge_faces])]
    owners = list(edge_faces.values())
    direction = ends - starts
    length = np.linalg.norm(direction, axis=1)
    cracks = 0
    for a, b in boundary:
        p, q = mesh.vertices[a], mesh.vertices[b]
        if np.array_equal(p, q):
            continue
        off_p = np.linalg.norm(np.cross(p - starts, direction), axis=1) / length
        off_q = np.linalg.norm(np.cross(q - starts, direction), axis=1) / length
        for index in np.flatnonzero((off_p < 1e-12) & (off_q < 1e-12)):
            middle = 0.5 * (p + q)
            both = 0
            for face in owners[index]:
                _, u, v = face_frame(corners[face])
                flat = shapely.Point(to_face_2d(middle[None], corners[face], u, v)[0])
                both += region(face).buffer(1e-12).covers(flat)
            cracks += both == 2
    assert cracks == 0


# -- the cases -----------------------------------------------------------------------------


def terrain_scene():
    ground = heightfield()
    objects = [
        box([0.5, 1.6, -0.8], [0.8, 0.6, 1.0]),
        sphere([-1.2, 1.8, 1.0], 0.6),
        sphere([1.8, 1.2, 1.6], 0.4),
    ]
    return ground, [ground, *objects]


def test_heightfield_point_light_matches_the_textbook_regions_and_10000_rays():
    ground, casters = terrain_scene()
    light = PointLight([1.0, 6.0, 0.5])
    shadow = shadow_on_surface(casters, light, ground)
    check_against_textbook(shadow, ground, casters, light, 12.0)
    check_rays(shadow, ground, casters, light, 10_000, 1, 12.0)
    check_seamless(shadow, ground)


def test_low_sun_long_shadows_and_hills_shadowing_valleys():
    ground, casters = terrain_scene()
    light = DirectionalLight([1.0, -0.3, 0.4])  # about 16 degrees above the horizon
    shadow = shadow_on_surface(casters, light, ground)
    alone = shadow_on_surface(casters[1:], light, ground)
    assert shadow.area > alone.area * 1.05  # the hills add their own shadows
    check_against_textbook(shadow, ground, casters, light, 12.0)
    check_rays(shadow, ground, casters, light, 3000, 2, 12.0)
    check_seamless(shadow, ground)


def test_l_shaped_terrain_under_a_low_sun():
    """A sheet over a region that is not convex: rays may pass under its
    border and meet it from below, so every face of it may cast."""
    full = heightfield(seed=5, n=10, half=3.0)
    centres = full.triangles_center
    keep = ~((centres[:, 0] > 0) & (centres[:, 2] > 0))
    ground = trimesh.Trimesh(full.vertices, full.faces[keep], process=False)
    ground.remove_unreferenced_vertices()
    casters = [ground, box([1.5, 1.0, -1.5], [0.6, 1.2, 0.6])]
    light = DirectionalLight([-0.8, -0.35, -0.9])
    shadow = shadow_on_surface(casters, light, ground)
    assert shadow.area > 0
    check_against_textbook(shadow, ground, casters, light, 9.0)
    check_rays(shadow, ground, casters, light, 2000, 7, 9.0)
    check_seamless(shadow, ground)


def test_single_sheet_is_recognised_only_where_it_holds():
    from shadowgeo.sheets import single_sheet
    from shadowgeo.topology import as_caster

    assert single_sheet(as_caster(heightfield()))
    assert single_sheet(as_caster(stairs()))  # a graph along a slanted direction
    full = grid(6, 1.0)
    keep = ~((full.triangles_center[:, 0] > 0) & (full.triangles_center[:, 2] > 0))
    assert not single_sheet(as_caster((full.vertices, full.faces[keep])))  # L-shaped
    assert not single_sheet(as_caster(sphere([0, 0, 0], 1.0)))  # closed
    # A sheet folded back over itself: its upper layer lies above its lower one.
    fold = grid(6, 1.0)
    bent = fold.vertices.copy()
    bent[:, 1] = np.where(fold.vertices[:, 0] > 0, 0.5, 0.0)
    bent[:, 0] = -np.abs(fold.vertices[:, 0])
    assert not single_sheet(as_caster((bent, fold.faces)))


def test_post_piercing_the_ground():
    ground = grid(6, 3.0)
    post = box([0.2, 0.5, 0.1], [0.4, 3.0, 0.4])  # from y = -1 to 2
    light = PointLight([2.0, 4.0, 1.0])
    shadow = shadow_on_surface([post], light, ground)
    check_against_textbook(shadow, ground, [post], light, 8.0)
    check_rays(shadow, ground, [post], light, 2000, 3, 8.0)
    # Only the part above the ground casts: the planar shadow says the same.
    square = [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]]
    planar = project_shadow(post, light, Plane([0, 1, 0], 0), receiver=square)
    assert shadow.area == pytest.approx(planar.area, rel=1e-9)


def test_stairs_with_a_pole():
    steps = stairs()
    pole = trimesh.creation.cylinder(radius=0.15, height=4.0, sections=12)
    pole.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))
    pole.apply_translation([1.5, 1.5, 1.5])
    light = PointLight([-2.0, 5.0, 2.5])
    casters = [steps, pole]
    shadow = shadow_on_surface(casters, light, steps)
    assert shadow.area > 0
    check_against_textbook(shadow, steps, casters, light, 6.0)
    check_rays(shadow, steps, casters, light, 2000, 4, 6.0)
    check_seamless(shadow, steps)


def test_tilted_torus_shadows_itself():
    torus = trimesh.creation.torus(
        major_radius=1.0, minor_radius=0.35, major_sections=20, minor_sections=10
    )
    torus.apply_transform(trimesh.transformations.rotation_matrix(0.6, [1, 0, 0]))
    light = PointLight([0.5, 4.0, 1.5])
    shadow = shadow_on_surface(torus, light, torus)
    assert shadow.area > 0
    check_against_textbook(shadow, torus, [torus], light, 3.0)
    check_rays(shadow, torus, [torus], light, 2000, 5, 3.0)
    check_seamless(shadow, torus)


def test_open_curved_sheet_lit_from_its_underside():
    sheet = grid(10, 2.0, lambda x, z: 0.3 * x**2 - 0.2 * np.sin(2 * z))
    sheet.faces = sheet.faces[:, ::-1]  # front faces down
    ball = sphere([0.3, -1.0, 0.2], 0.3)
    light = PointLight([-0.5, -3.0, 0.4])
    casters = [sheet, ball]
    shadow = shadow_on_surface(casters, light, sheet)
    assert shadow.area > 0
    proper = shadow.mesh.area_faces > 1e-14  # collinear edge splits have no normal
    assert np.all(shadow.mesh.face_normals[proper, 1] < 0)  # wound as their faces
    check_against_textbook(shadow, sheet, casters, light, 6.0)
    check_rays(shadow, sheet, casters, light, 2000, 6, 6.0)


def test_separate_casters_settled_at_once_know_what_each_works_out_alone():
    """The closedness and boxes of many casters, worked out together, are
    each caster's own: open and closed meshes, some with vertices no face
    uses (outside the box), one that knew its closedness already."""
    from shadowgeo.surface import _settle_casters
    from shadowgeo.topology import Caster

    rng = np.random.default_rng(4)
    meshes = []
    for index in range(9):
        box = trimesh.creation.box(extents=rng.uniform(0.5, 2, 3))
        vertices, faces = box.vertices + rng.uniform(-9, 9, 3), box.faces
        if index % 3 == 1:
            faces = faces[:-1]  # open
        if index % 3 == 2:  # a far vertex no face uses
            vertices = np.vstack([vertices, [100.0, -100.0, 100.0]])
        meshes.append((vertices, faces))
    casters = [Caster(v, f) for v, f in meshes]
    casters[4] = Caster(*meshes[4], closed=True)  # told (wrongly): kept as told
    _settle_casters(casters)
    for k, (caster, (vertices, faces)) in enumerate(zip(casters, meshes, strict=True)):
        alone = Caster(vertices, faces)
        assert np.array_equal(caster.bounds, alone.bounds)
        assert caster.is_closed == (True if k == 4 else alone.is_closed)


@pytest.mark.parametrize(
    "light",
    [DirectionalLight([0.35, -1.0, 0.25]), PointLight([0.4, 7.0, -0.3])],
    ids=["sun", "point"],
)
def test_many_floating_boxes_cut_each_face_by_its_own_outlines(light):
    # Forty boxes over a floor, their shadows over one another and over the
    # boxes below them: every outline is cut in one go (OutlineSet; in the
    # sun's one frame, or each in its own frame from a point light), each
    # face by the outlines of the casters wholly in front of it only. The
    # floor's shadow is the planar one, clipped.
    rng = np.random.default_rng(5)
    floor = grid(12, 3.0)
    casters = [
        box([*rng.uniform(-2.2, 2.2, 1), rng.uniform(0.6, 2.5), *rng.uniform(-2.2, 2.2, 1)],
            rng.uniform(0.1, 0.5, 3))
        for _ in range(40)
    ]  # fmt: skip
    on_floor = shadow_on_surface(casters, light, floor)
    square = [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]]
    planar = project_shadow(
        trimesh.util.concatenate(casters), light, Plane([0, 1, 0], 0), receiver=square
    )
    assert on_floor.diagnostics.n_outlined_casters == 40
    assert on_floor.area == pytest.approx(planar.area, rel=1e-9)
    # every surface at once: the boxes shadow one another, rays agree
    scene = trimesh.util.concatenate([floor, *casters])
    everything = shadow_on_surface(casters, light, scene)
    floor_faces = len(floor.faces)
    assert everything.fraction[:floor_faces] == pytest.approx(on_floor.fraction, abs=1e-9)
    assert np.any(everything.fraction[floor_faces:][everything.fraction[floor_faces:] < 1] > 0)
    check_rays(everything, scene, casters, light, 3000, 6, 3.0)


def test_a_lamp_over_a_floor_far_wider_than_it_is_high_casts_by_outlines_exactly():
    # A floor of two triangles reaching far behind a low lamp in every
    # caster's frame: each caster's outline still cuts the part of the floor
    # deep enough to be shaded (no triangle pair is clipped), exactly.
    floor = trimesh.Trimesh(
        [[-20, 0, 20], [20, 0, 20], [20, 0, -20], [-20, 0, -20]], [[0, 1, 2], [0, 2, 3]]
    )
    casters = [sphere([1.0, 0.8, 0.5], 0.5, 5), box([-1.5, 0.6, -0.8], [0.6, 1.2, 0.4])]
    lamp = PointLight([0.0, 3.0, 0.0])
    shadow = shadow_on_surface(casters, lamp, floor)
    planar = project_shadow(trimesh.util.concatenate(casters), lamp, Plane([0, 1, 0], 0))
    assert shadow.area == pytest.approx(planar.area, rel=1e-12)
    assert shadow.diagnostics.n_outlined_casters == 2
    assert shadow.diagnostics.n_clipped_pairs == 0
    ours = shapely.union_all([shapely.Polygon(t[:, [0, 2]]) for t in shadow.mesh.triangles])
    theirs = shapely.union_all([shapely.Polygon(t[:, [0, 2]]) for t in planar.mesh.triangles])
    assert ours.symmetric_difference(theirs).area < 1e-10 * planar.area


@pytest.mark.parametrize("sunk", [0.0, 1e-3], ids=["standing", "sunk"])
@pytest.mark.parametrize(
    "sun",
    [DirectionalLight([1.0, -0.2, 0.3]), PointLight([-9.0, 1.5, 2.0])],
    ids=["low sun", "low lamp"],
)
def test_boxes_standing_on_the_floor_cast_by_their_outlines_exactly(sunk, sun):
    # Boxes standing on the floor (their bottoms on its plane) under a low
    # sun (about 11 degrees up) or a low lamp are cut to it by their
    # outlines, not triangle by triangle; boxes sunk into it (far past the
    # tolerance) by their triangles, clipped to the floor's front. Either
    # way the floor's shadow is the planar one.
    rng = np.random.default_rng(8)
    floor = grid(10, 3.0)
    casters = []
    for _ in range(12):
        size = rng.uniform(0.1, 0.4, 3)
        centre = [*rng.uniform(-2.4, 2.4, 1), size[1] / 2 - sunk, *rng.uniform(-2.4, 2.4, 1)]
        casters.append(box(centre, size))
    shadow = shadow_on_surface(casters, sun, floor)
    square = [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]]
    above = [
        trimesh.intersections.slice_mesh_plane(c, [0, 1, 0], [0, 0, 0], cap=True) for c in casters
    ]
    planar = project_shadow(
        trimesh.util.concatenate(above), sun, Plane([0, 1, 0], 0), receiver=square
    )
    assert shadow.area == pytest.approx(planar.area, rel=1e-9)
    assert shadow.diagnostics.n_outlined_casters == 12
    if sunk:
        assert shadow.diagnostics.n_clipped_pairs > 0
    else:
        assert shadow.diagnostics.n_clipped_pairs == 0  # every box by its outline


@pytest.mark.parametrize(
    "light",
    [
        PointLight([0.7, 5.0, -0.4]),
        DirectionalLight([0.3, -1.0, 0.2]),
        DirectionalLight([1, -0.05, 0.1]),
    ],
    ids=["point", "directional", "grazing"],
)
def test_flat_grid_equals_project_shadow_clipped_to_the_grid(light):
    floor = grid(16, 3.0)
    casters = [sphere([0.2, 1.5, 0.1], 0.7, 2), box([-1.5, 0.5, 1.2], [0.5, 1.0, 0.5])]
    shadow = shadow_on_surface(casters, light, floor)
    square = [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]]
    planar = project_shadow(
        trimesh.util.concatenate(casters), light, Plane([0, 1, 0], 0), receiver=square
    )
    assert planar.area > 0
    assert shadow.area == pytest.approx(planar.area, rel=1e-9)
    ours = shapely.union_all([shapely.Polygon(t[:, [0, 2]]) for t in shadow.mesh.triangles])
    theirs = shapely.union_all([shapely.Polygon(t[:, [0, 2]]) for t in planar.mesh.triangles])
    assert ours.symmetric_difference(theirs).area < 1e-9 * planar.area
    check_seamless(shadow, floor)
    # The sphere and box went by their outlines, covering some faces whole.
    assert shadow.diagnostics.n_outlined_casters == 2
    if isinstance(light, PointLight):
        assert shadow.diagnostics.n_full_faces > 0


def test_offset_lifts_along_each_face_normal_without_opening_cracks():
    ground, casters = terrain_scene()
    light = PointLight([1.0, 6.0, 0.5])
    flat = shadow_on_surface(casters, light, ground)
    lifted = shadow_on_surface(casters, light, ground, offset=0.01)
    np.testing.assert_array_equal(lifted.face_index, flat.face_index)
    np.testing.assert_array_equal(lifted.mesh.faces, flat.mesh.faces)  # still shared
    normals = ground.face_normals[lifted.face_index]
    corners = ground.vertices[ground.faces[lifted.face_index, 0]]
    triangles = lifted.mesh.vertices[lifted.mesh.faces]
    heights = np.einsum("ijk,ik->ij", triangles - corners[:, None], normals)
    # Points inside a face or on an edge of two faces sit exactly on the offset
    # planes; only mesh vertices of three or more faces may compromise.
    on_plane = np.abs(heights - 0.01) < 1e-9
    gaps = np.linalg.norm(flat.mesh.vertices[:, None] - ground.vertices[None], axis=2)
    at_corner = gaps.min(axis=1) < 1e-12
    assert np.all(on_plane[~at_corner[lifted.mesh.faces]])
    assert np.all(np.abs(heights - 0.01) < 0.01 * 0.25)
    assert lifted.area == pytest.approx(flat.area, rel=1e-12)  # measured in the faces


@pytest.mark.parametrize("shift, scale", [(1e6, 1.0), (0.0, 1e-3), (-3e4, 1e3)])
def test_moving_or_scaling_the_scene_changes_nothing(shift, scale):
    ground, casters = terrain_scene()
    light = PointLight([1.0, 6.0, 0.5])
    reference = shadow_on_surface(casters, light, ground)

    def moved(mesh):
        return trimesh.Trimesh(mesh.vertices * scale + shift, mesh.faces, process=False)

    ground2 = moved(ground)
    casters2 = [ground2, *(moved(c) for c in casters[1:])]
    shadow = shadow_on_surface(casters2, PointLight(light.position * scale + shift), ground2)
    assert shadow.area == pytest.approx(reference.area * scale**2, rel=1e-8)
    np.testing.assert_allclose(shadow.fraction, reference.fraction, atol=1e-8)


def test_spot_cone_and_range_limit_the_shadow():
    floor = grid(12, 3.0)
    ball = sphere([0.5, 1.2, 0.0], 0.6, 2)
    position = [0.5, 4.0, 0.0]
    full = shadow_on_surface(ball, PointLight(position), floor)
    spot = SpotLight(position, [0.3, -1.0, 0.0], cut_off_angle=0.25)
    coned = shadow_on_surface(ball, spot, floor)
    assert 0 < coned.area < full.area
    directions = coned.mesh.vertices - spot.position
    cosines = directions @ spot.direction / np.linalg.norm(directions, axis=1)
    assert np.all(cosines >= math.cos(0.25) - 1e-9)
    ranged = shadow_on_surface(ball, PointLight(position, radius=4.05), floor)
    assert 0 < ranged.area < full.area
    assert np.all(np.linalg.norm(ranged.mesh.vertices - position, axis=1) <= 4.05 + 1e-9)
    # With a fine chord both tessellate the lit disc closely: they agree.
    fine = Tolerance.for_points(floor.bounds, [position], chord=1e-7)
    ranged = shadow_on_surface(ball, PointLight(position, radius=4.05), floor, tolerance=fine)
    planar = project_shadow(
        ball, PointLight(position, radius=4.05), Plane([0, 1, 0], 0), tolerance=fine
    )
    assert ranged.area == pytest.approx(planar.area, rel=1e-6)


@pytest.mark.parametrize("chord", [None, 1e-7])
def test_faces_the_range_surely_holds_skip_its_disc_and_change_nothing(monkeypatch, chord):
    """A point light of radius 4.15 over a floor: every face _inside_range
    passes is one _disc_near leaves alone, faces of both kinds occur, and the
    shadow is the same, bit for bit, as with every face cut by the disc."""
    import shadowgeo.surface as surface_module

    floor = grid(12, 3.0)
    ball = sphere([0.5, 1.2, 0.0], 0.6, 2)
    light = PointLight([0.5, 4.0, 0.0], radius=4.15)  # its disc on the floor just holds the shadow
    tolerance = None
    if chord is not None:  # a fine chord: many sides, the sagitta far below it
        tolerance = Tolerance.for_points(floor.bounds, [light.position], chord=chord)
    original = surface_module._SurfaceProjector._inside_range
    seen = []

    def checked(self, faces, outlines):
        inside = original(self, faces, outlines)
        for face, outline, held in zip(faces, outlines, inside, strict=True):
            if held:
                assert surface_module._disc_near(self._range_disc(face), outline) is None
        seen.extend(inside.tolist())
        return inside

    monkeypatch.setattr(surface_module._SurfaceProjector, "_inside_range", checked)
    quick = shadow_on_surface(ball, light, floor, tolerance=tolerance)
    assert any(seen) and not all(seen)
    monkeypatch.setattr(
        surface_module._SurfaceProjector,
        "_inside_range",
        lambda self, faces, outlines: np.zeros(len(faces), dtype=bool),
    )
    every = shadow_on_surface(ball, light, floor, tolerance=tolerance)
    assert quick.area > 0
    assert np.array_equal(quick.mesh.vertices, every.mesh.vertices)
    assert np.array_equal(quick.mesh.faces, every.mesh.faces)


def test_light_in_the_plane_of_the_faces_receives_nothing_and_stays_finite():
    floor = grid(4, 1.0)
    light = PointLight([3.0, 0.0, 0.5])
    post = box([2.0, 0.5, 0.5], [0.2, 1.0, 0.2])
    shadow = shadow_on_surface([post, floor], light, floor)
    assert shadow.area == 0.0 and len(shadow.mesh.faces) == 0
    assert np.all(shadow.fraction == 1.0)  # edge-on faces get no light
    grazing = shadow_on_surface([post], DirectionalLight([1.0, 0.0, 0.0]), floor)
    assert grazing.area == 0.0 and np.all(np.isfinite(grazing.fraction))


def test_light_inside_a_caster_is_an_error():
    floor = grid(4, 2.0)
    with pytest.raises(GeometryError, match="inside the closed caster"):
        shadow_on_surface([sphere([0, 2, 0], 1.0)], PointLight([0, 2.1, 0]), floor)


def test_faces_turned_away_are_wholly_shadowed_and_inputs_may_be_pairs():
    ball = sphere([0, 0, 0], 1.0, 2)
    light = DirectionalLight([0, -1, 0])
    shadow = shadow_on_surface([], light, (ball.vertices, ball.faces))
    away = ball.face_normals @ [0, 1, 0] < 0
    assert np.all(shadow.fraction[away] == 1.0)
    assert np.all(shadow.fraction[~away & (ball.face_normals[:, 1] > 1e-9)] == 0.0)
    pair = shadow_on_surface((ball.vertices, ball.faces), light, ball)
    assert pair.area == 0.0  # a convex ball does not shadow its own lit side


@pytest.mark.parametrize(
    "light", [PointLight([0.3, 6.0, -0.2]), DirectionalLight([0.4, -1.0, 0.25])]
)
def test_closed_casters_silhouettes_found_together_are_each_ones_alone(light):
    # Boxes, spheres and a torus (a caster with two loops, one inside the
    # other from above) stacked: each one's front faces and loops, in order
    # and from the same corner, as silhouette_loops gives them one by one.
    from shadowgeo.silhouette import light_homogeneous, silhouette_loops
    from shadowgeo.surface import closed_silhouettes
    from shadowgeo.topology import Caster

    rng = np.random.default_rng(11)
    meshes = [
        trimesh.creation.box(extents=rng.uniform(0.2, 1.0, 3)),
        trimesh.creation.icosphere(subdivisions=2, radius=0.6),
        trimesh.creation.torus(1.0, 0.3),
        trimesh.creation.box(extents=[2.0, 0.1, 0.5]),
        trimesh.creation.icosphere(subdivisions=1, radius=0.3),
    ]
    casters = []
    for mesh in meshes:
        mesh.apply_translation(rng.uniform(-3, 3, 3))
        casters.append(Caster(mesh.vertices, mesh.faces))
    together = closed_silhouettes(casters, light)
    for caster, (front, loops) in zip(casters, together, strict=True):
        alone_front = caster.facing(light_homogeneous(caster, light)) > 0
        alone_loops, _ = silhouette_loops(caster, alone_front)
        assert np.array_equal(front, alone_front)
        assert len(loops) == len(alone_loops) >= 1
        for loop, alone in zip(loops, alone_loops, strict=True):
            assert np.array_equal(loop, alone)
