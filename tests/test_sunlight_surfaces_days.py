"""Sunlight on walls and roofs day by day (issue 33 item 5): each day's study
the same whether the days run one after another here or as tasks on a Dask
``LocalCluster`` of two worker processes, bit for bit; and each day's hours
at points on the walls and roofs against rays cast to the sun."""

from __future__ import annotations

import datetime as dt

import numpy as np
import trimesh
from needs import need

from shadowgeo import surface_sun_study_by_day
from shadowgeo.sun import hourly

SITE = dict(latitude=52.0, longitude=4.37, up="Z")


def _town() -> list[trimesh.Trimesh]:
    """Four boxes of different heights, close enough to shade each other."""
    boxes = []
    for low, high in [
        ([0, 0, 0], [10, 8, 12]),
        ([14, -2, 0], [22, 6, 30]),
        ([-6, 12, 0], [8, 20, 18]),
        ([26, 4, 0], [32, 14, 20]),
    ]:
        low_corner, high_corner = np.asarray(low, float), np.asarray(high, float)
        mesh = trimesh.creation.box(extents=high_corner - low_corner)
        mesh.apply_translation((low_corner + high_corner) / 2)
        boxes.append(mesh)
    return boxes


def _receiver(town):
    merged = trimesh.util.concatenate(town)
    keep = merged.face_normals[:, 2] > -0.5  # walls and roofs, not the bottoms
    return merged, (np.asarray(merged.vertices), np.asarray(merged.faces[keep]))


def _times():
    first = hourly(dt.datetime(2026, 3, 21, tzinfo=dt.UTC), dt.datetime(2026, 3, 22, tzinfo=dt.UTC))
    second = hourly(
        dt.datetime(2026, 6, 21, tzinfo=dt.UTC), dt.datetime(2026, 6, 22, tzinfo=dt.UTC)
    )
    return first + second


def _same(first, second) -> bool:
    """Two studies equal bit for bit: sun, shadows and every level's loops."""
    if first.times != second.times or not np.array_equal(first.directions, second.directions):
        return False
    for a, b in zip(first.shadows, second.shadows, strict=True):
        if not all(
            np.array_equal(getattr(a, name), getattr(b, name))
            for name in ("triangles", "face", "dark", "fraction")
        ):
            return False
    for mine, theirs in zip(first.levels, second.levels, strict=True):
        if mine.keys() != theirs.keys():
            return False
        for k in mine:
            loops_a = [loop for part in mine[k] for loop in part]
            loops_b = [loop for part in theirs[k] for loop in part]
            if len(loops_a) != len(loops_b) or not all(
                np.array_equal(x, y) for x, y in zip(loops_a, loops_b, strict=True)
            ):
                return False
    return True


def test_days_on_a_dask_cluster_of_two_processes_equal_the_serial_days_bit_for_bit():
    need("dask")
    from dask.distributed import Client, LocalCluster

    town = _town()
    _, receiver = _receiver(town)
    times = _times()
    done = []
    serial = surface_sun_study_by_day(
        town, receiver, times, **SITE, progress=lambda k, n: done.append((k, n))
    )
    assert list(serial) == [dt.date(2026, 3, 21), dt.date(2026, 6, 21)]
    assert done == [(1, 2), (2, 2)]
    with (
        LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        Client(cluster) as client,
    ):
        on_dask = surface_sun_study_by_day(town, receiver, times, **SITE, scheduler=client)
        # the same meshes again at once on the same client: their first sending,
        # let go as the first study returned, must not take the second's with it
        # (sent under one key, as content-hashed scatters were, its tasks were
        # cancelled for "lost dependencies")
        again = [
            surface_sun_study_by_day(town, receiver, times, **SITE, levels=False, scheduler=client)
            for _ in range(3)
        ]
    assert list(on_dask) == list(serial)
    assert all(_same(serial[day], on_dask[day]) for day in serial)
    for study in again:
        for day in serial:
            assert np.array_equal(study[day].mean_hours(), serial[day].mean_hours())


def test_each_days_hours_at_wall_and_roof_points_agree_with_rays():
    town = _town()
    merged, receiver = _receiver(town)
    vertices, faces = receiver
    by_day = surface_sun_study_by_day(town, receiver, _times(), **SITE)
    rng = np.random.default_rng(5)
    on = rng.integers(0, len(faces), 400)
    weights = rng.dirichlet([1, 1, 1], 400)
    points = np.einsum("pk,pkd->pd", weights, vertices[faces[on]])
    normals = trimesh.triangles.normals(vertices[faces[on]])[0]
    rays = trimesh.ray.ray_triangle.RayMeshIntersector(merged)
    for study in by_day.values():
        traced = np.zeros(len(points))
        for direction in study.directions:
            front = normals @ -direction > 0
            lifted = points + 1e-6 * normals
            hit = rays.intersects_any(lifted, np.tile(-direction, (len(points), 1)))
            traced += front & ~hit
        exact = study.sunlit_hours(points, on)
        # a point within rounding of a shadow's edge may go either way
        assert np.mean(exact == traced) > 0.99
        assert np.abs(exact - traced).max() <= 1.0
