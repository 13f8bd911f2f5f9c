"""The compiled loops as a setting (issue 31): shadowgeo.compiled's rule picks
numpy for a small job and numba for a large one whatever is imported, the
override (argument, block, environment) wins over it, and the numpy and
compiled walks give the same shadows bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import shadowgeo as sg
from shadowgeo import compiled
from shadowgeo.compiled import compiled_loops, current_mode, use_compiled

GROUND = sg.Plane([0, 1, 0], 0)


@pytest.fixture(autouse=True)
def _no_environment(monkeypatch):
    monkeypatch.delenv(compiled.ENVIRONMENT, raising=False)


def test_the_rule_picks_numpy_for_a_small_job_and_numba_for_a_large_one():
    import shadowgeo.kernels  # noqa: F401  (loaded already: that no longer decides)

    assert current_mode() == "auto"
    assert not use_compiled("walk", 4096)
    assert not use_compiled("walk", compiled.WALK_ITEMS - 1)
    assert use_compiled("walk", compiled.WALK_ITEMS)
    assert not use_compiled("certificate", 0)  # no light needs it: numba stays out
    assert use_compiled("certificate", 1)


def test_the_override_argument_block_environment_in_that_order(monkeypatch):
    assert use_compiled("walk", 1, mode="always") and not use_compiled("walk", 0, mode="always")
    assert not use_compiled("walk", 10**9, mode="never")
    monkeypatch.setenv(compiled.ENVIRONMENT, " Never ")
    assert current_mode() == "never" and not use_compiled("walk", 10**9)
    with compiled_loops("always"):
        assert use_compiled("walk", 1)
        with compiled_loops("auto"):
            assert not use_compiled("walk", 1)
        assert use_compiled("walk", 1, mode="always")
        assert not use_compiled("walk", 1, mode="never")
    assert current_mode() == "never"  # the block's setting is gone after it


def test_a_mode_it_does_not_know_is_an_error_naming_where_it_came_from(monkeypatch):
    monkeypatch.setenv(compiled.ENVIRONMENT, "fast")
    with pytest.raises(ValueError, match=r"SHADOWGEO_COMPILED='fast': expected one of auto"):
        current_mode()
    with pytest.raises(ValueError, match="compiled_loops='yes'"), compiled_loops("yes"):
        pass
    with pytest.raises(ValueError, match="mode='on'"):
        use_compiled("walk", 5, mode="on")


@pytest.fixture
def counted(monkeypatch):
    """Calls of the compiled walks, by name."""
    from shadowgeo import kernels

    calls = {"cycle_walk": 0, "successors": 0, "whole_loops": 0}
    for name in calls:
        real = getattr(kernels, name)

        def spy(*args, _real=real, _name=name):
            calls[_name] += 1
            return _real(*args)

        monkeypatch.setattr(kernels, name, spy)
    return calls


def _scenes():
    ball = trimesh.creation.icosphere(subdivisions=4)
    ball.apply_translation([0, 2, 0])
    boxes = [trimesh.creation.box(extents=[0.5, 1, 0.5]) for _ in range(64)]
    for k, box in enumerate(boxes):
        box.apply_translation([k % 8, 1, k // 8])
    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3)
    torus.apply_transform(trimesh.transformations.rotation_matrix(0.7, [1, 0, 0]))
    torus.apply_translation([0, 2, 0])
    lights = [sg.PointLight([1, 9, 2]), sg.DirectionalLight([0.3, -1, 0.2])]
    return {"ball": ball, "city": trimesh.util.concatenate(boxes), "torus": torus}, lights


def _arrays(shadow):
    """Everything a Shadow holds as arrays, for exact comparison."""
    return [shadow.area, *[ring for part in shadow.polygons for ring in part]]


def _same(one, other):
    assert len(one) == len(other)
    for a, b in zip(one, other, strict=True):
        assert np.array_equal(a, b)


def test_never_and_always_cast_the_same_shadows_bit_for_bit(counted):
    # (``counted`` has imported the kernels: that must not decide)
    scenes, lights = _scenes()
    for name, caster in scenes.items():
        results = {}
        for chosen in ("never", "always", "auto"):
            with compiled_loops(chosen):
                before = dict(counted)
                batch = sg.project_shadow(caster, lights, GROUND)
                single = sg.project_shadow(caster, lights[0], GROUND)
                outline = sg.silhouette(caster, lights[1])
                surface = sg.shadow_on_surface([caster], lights[0], caster)
                walked = sum(counted.values()) - sum(before.values())
            results[chosen] = (
                [a for shadow in [*batch, single] for a in _arrays(shadow)]
                + [np.asarray(loop) for loop in outline.loops]
                + [surface.mesh.vertices, surface.mesh.faces, surface.fraction]
            )
            if chosen == "always":
                assert walked > 0, name  # the compiled walks did run
            else:  # small jobs: numpy, though the kernels are imported
                assert walked == 0, (name, chosen)
        _same(results["never"], results["always"])
        _same(results["auto"], results["always"])


def test_a_dented_caster_certified_or_united_has_the_same_shadow(counted):
    """The certificate's numpy alternative is the 2-D union: the same region
    to rounding (not the same bits), and numba left out under never."""
    mesh = trimesh.creation.icosphere(subdivisions=4)
    mesh.vertices[mesh.vertices[:, 1] > 0.6] *= [1, 0.6, 1]  # a dent: folds inside the outline
    mesh.apply_translation([0.3, 2.5, -0.2])
    rng = np.random.default_rng(8)
    lights = [sg.PointLight(p) for p in rng.uniform([-3, 6, -3], [3, 9, 3], (20, 3))]
    shadows = {}
    for chosen in ("never", "auto", "always"):
        with compiled_loops(chosen):
            before = counted["whole_loops"]
            shadows[chosen] = sg.project_shadow(mesh, lights, GROUND)
            certified = counted["whole_loops"] - before
        assert (certified > 0) == (chosen != "never"), chosen
    # the walks are the only other difference between auto and always: none
    _same(
        [a for shadow in shadows["auto"] for a in _arrays(shadow)],
        [a for shadow in shadows["always"] for a in _arrays(shadow)],
    )
    for united, certified in zip(shadows["never"], shadows["auto"], strict=True):
        assert united.area == pytest.approx(certified.area, rel=1e-12)
        difference = united.to_shapely().symmetric_difference(certified.to_shapely()).area
        assert difference < 1e-9 * united.area


def test_never_keeps_numba_out_of_a_process_whose_shadows_would_load_it():
    script = """
import sys
import trimesh
import shadowgeo as sg
mesh = trimesh.creation.icosphere(subdivisions=4)
mesh.vertices[mesh.vertices[:, 1] > 0.6] *= [1, 0.6, 1]
mesh.apply_translation([0.3, 2.5, -0.2])
lights = [sg.PointLight([x, 8, 1]) for x in (-2.0, -1.0, 0.0, 1.0, 2.0)]
sg.project_shadow(mesh, lights, sg.Plane([0, 1, 0], 0))
print("numba" in sys.modules)
"""
    import os
    import subprocess
    import sys

    loaded = {}
    for chosen in ("never", "auto"):
        environment = {**os.environ, compiled.ENVIRONMENT: chosen}
        result = subprocess.run(
            [sys.executable, "-c", script],
            capture_output=True,
            text=True,
            timeout=300,
            check=True,
            env=environment,
        )
        loaded[chosen] = result.stdout.strip()
    assert loaded == {"never": "False", "auto": "True"}


def test_the_command_refuses_a_mode_it_does_not_know_as_bad_usage(monkeypatch, capsys):
    from needs import ROOT

    from cli.main import main

    monkeypatch.setenv(compiled.ENVIRONMENT, "sometimes")
    assert main(["info", str(ROOT / "examples" / "scenes" / "courtyard.x3d")]) == 2
    assert "SHADOWGEO_COMPILED='sometimes': expected one of auto, always, never" in (
        capsys.readouterr().err
    )
    monkeypatch.setenv(compiled.ENVIRONMENT, "never")
    assert main(["info", str(ROOT / "examples" / "scenes" / "courtyard.x3d")]) == 0
