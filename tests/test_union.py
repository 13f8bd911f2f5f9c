"""The one 2-D union, ``shadowgeo.plane2d.unite``: every road it takes (one
Clipper2 call, cells of a grid, the arrangement of convex loops) checks
Clipper2's budgets before Clipper2 runs, its forms agree with each other and
with GEOS, and no other module builds a Clipper2 region from loops itself.

References: hand-counted sweep work (k unit squares in a row: 12 k^2 steps,
as tests/test_slow_inputs.py derives) and shapely's unions (GEOS)."""

from __future__ import annotations

import ast

import numpy as np
import pytest
import shapely
from needs import ROOT

from shadowgeo import plane2d
from shadowgeo.errors import BudgetError
from shadowgeo.plane2d import FlatParts, parts_area, unite
from shadowgeo.plane2d import budget as budget_module
from shadowgeo.plane2d import union as union_module

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
# the same square with a fifth corner halfway along its bottom: not strictly
# convex, so the arrangement hands it back and Clipper2 unites it
NOTCHED = np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def row(loop: np.ndarray, count: int, pitch: float = 2.0, rise: float = 0.0) -> list[np.ndarray]:
    """``count`` copies of ``loop`` side by side along x, ``pitch`` apart,
    each ``rise`` above the one before."""
    return [loop + [pitch * index, rise * index] for index in range(count)]


def one_group_each(loops: list[np.ndarray]):
    return lambda: np.arange(len(loops))


def geos_area(loops: list[np.ndarray]) -> float:
    return float(shapely.union_all([shapely.Polygon(loop) for loop in loops]).area)


@pytest.fixture
def small_sweep_budget(monkeypatch):
    """A sweep budget of 100 steps: a row of three unit squares (108 steps)
    is past it, two (48) are not."""
    monkeypatch.setattr(budget_module, "MAX_UNION_SWEEP", 100)
    monkeypatch.setattr(union_module, "MAX_UNION_SWEEP", 100)


@pytest.mark.parametrize(
    ("loops", "groups", "form"),
    [
        (row(SQUARE, 3), None, "region"),  # one Clipper2 call
        (row(SQUARE, 3), None, "parts"),
        (row(NOTCHED, 3), True, "parts"),  # in groups, few: one call
        (row(NOTCHED, 2001), True, "parts"),  # in groups, many: cell by cell
        (row(NOTCHED, 2001), True, "region"),
        (row(SQUARE, 64), True, "region"),  # the arrangement's loops, filled
    ],
    ids=["one call", "one call, parts", "groups", "cells", "cells, region", "arranged, region"],
)
def test_every_road_to_clipper2_checks_the_sweep_budget(small_sweep_budget, loops, groups, form):
    with pytest.raises(BudgetError, match="MAX_UNION_SWEEP"):
        unite(loops, groups=one_group_each(loops) if groups else None, form=form)


def test_the_arrangement_unites_without_clipper2_and_without_its_budget(small_sweep_budget):
    loops = row(SQUARE, 64)  # 64 squares apart: the arrangement's, no Clipper2 call
    flat = unite(loops, groups=one_group_each(loops), form="flat")
    assert isinstance(flat, FlatParts)
    assert flat.area == pytest.approx(64.0, rel=1e-15)
    assert parts_area(unite(loops, groups=one_group_each(loops), form="parts")) == pytest.approx(
        64.0, rel=1e-15
    )


def test_two_squares_are_within_the_small_budget(small_sweep_budget):
    assert unite(row(SQUARE, 2)).area() == pytest.approx(2.0)


@pytest.mark.parametrize(
    "loops",
    [
        [SQUARE * 3, SQUARE * 3 + [1.5, 1.0], SQUARE + [7.0, 0.0]],  # one call
        [loop * 1e4 for loop in row(SQUARE * 3, 80, pitch=2.5, rise=0.25)],  # arranged, overlapping
        [loop * 1e4 for loop in row(NOTCHED * 3, 2100, pitch=2.5, rise=0.25)],  # cells, overlapping
    ],
    ids=["one call", "arranged", "cells"],
)
def test_the_forms_agree_with_each_other_and_with_geos(loops):
    groups = one_group_each(loops)
    expected = geos_area(loops)
    region = unite(loops, groups=groups)
    parts = unite(loops, groups=groups, form="parts")
    flat = unite(loops, groups=groups, form="flat")
    flat_area = flat.area if isinstance(flat, FlatParts) else parts_area(flat)
    assert isinstance(flat, FlatParts) == (len(loops) == 80)  # only the arrangement's are flat
    for area in (region.area(), parts_area(parts), flat_area, unite(loops).area()):
        assert area == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("arguments", [{"rule": "evenodd"}, {"cells": np.zeros(2, np.int64)}])
def test_groups_unite_by_the_positive_rule_alone(arguments):
    loops = [SQUARE, SQUARE + 0.5]
    with pytest.raises(ValueError, match="positive rule, without cells"):
        unite(loops, groups=one_group_each(loops), **arguments)


def test_the_rules_count_windings_as_geos_does():
    # a square inside a larger one, both counter-clockwise: winding 2 inside the small one
    loops = [SQUARE * 4, SQUARE + 1.0]
    assert unite(loops).area() == pytest.approx(16.0)
    assert unite(loops, rule="nonzero").area() == pytest.approx(16.0)
    assert unite(loops, rule="evenodd").area() == pytest.approx(15.0)


# The one module that builds a Clipper2 region from loops: the union's.
OWN_REGIONS = {"shadowgeo/plane2d/union.py"}


def _region_builders(path) -> list[int]:
    """Lines of ``path`` that call ``CrossSection(...)`` with contours."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and getattr(node.func, "id", getattr(node.func, "attr", None)) == "CrossSection"
        and (node.args or node.keywords)
    ]


def test_no_other_module_builds_a_region_from_loops():
    found = {}
    for path in sorted((ROOT / "shadowgeo").rglob("*.py")):
        lines = _region_builders(path)
        name = path.relative_to(ROOT).as_posix()
        if lines and name not in OWN_REGIONS:
            found[name] = lines
    assert not found, f"CrossSection(loops) outside plane2d.unite: {found}"
    assert _region_builders(ROOT / "shadowgeo" / "plane2d" / "union.py")  # the scan sees them


def test_the_package_gathers_its_modules_names():
    for module in ("predicates", "budget", "nesting", "union", "triangulation"):
        names = getattr(plane2d, module).__all__
        assert set(names) <= set(plane2d.__all__), module
