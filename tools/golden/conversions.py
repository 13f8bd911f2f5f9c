"""Conversion cases: a scene file through ``shadowgeo convert IN OUT`` with no flags.

That command is ``load`` (default budget), ``add_shadows`` (planar, the
scene's lights, receivers found, default tolerance) and ``save``
(:func:`shadowgeo.batch.shadowed` with default ``ConvertOptions``); the cases
make the same public calls, so they run at any commit that has them. The
example scenes also go through ``--method volume``.

A writer rewrites each relative url of the scene for the folder it writes to
(:mod:`shadowgeo.io.x3d.urls`), so the bytes depend on where the input and
the output lie relative to each other. The inputs are therefore copied into a
fixed layout under a scratch folder (``in/examples/scenes/``,
``in/corpus/<collection>/...``) and written to the mirror of that layout under
``out/<method>/``: the same bytes whatever the repository's or the corpus's path.
"""

from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

from .digest import Digest, error, sha256

FORMATS = (".x3d", ".glb", ".usda")

# 30 corpus scenes, chosen once by hand for lights and shadows (most have
# lights; the rest are lit by the default sun), spread over the collections and
# encodings; each converts in well under a second.
CORPUS = (
    # castle-demo-models: X3D XML
    "castle-demo-models/lights_materials/light_street_lights_radius.x3d",
    "castle-demo-models/lights_materials/shading_smooth_even_on_flat_normals.x3d",
    "castle-demo-models/navigation/avatar_climb_stairs_geometry.x3d",
    "castle-demo-models/blender/simple/test1.x3d",
    "castle-demo-models/x3d/axis.x3d",
    "castle-demo-models/x3d/matrix_transform.x3d",
    "castle-demo-models/x3d/car/car.x3d",
    "castle-demo-models/x3d/regular_labirynth.x3d",
    "castle-demo-models/multi_texturing/primitives.x3d",
    # castle-demo-models-classic: ClassicVRML (.x3dv, gzip .x3dvz) and VRML 97 (.wrl)
    "castle-demo-models-classic/lights_materials/lights.x3dv",
    "castle-demo-models-classic/lights_materials/light_radius.wrl",
    "castle-demo-models-classic/lights_materials/directional_light_scope.wrl",
    "castle-demo-models-classic/lights_materials/raytracer/alien_mirror.wrl",
    "castle-demo-models-classic/lights_materials/specular_demo.wrl",
    "castle-demo-models-classic/lights_materials/non_global_lights_test.x3dv",
    "castle-demo-models-classic/lights_materials/light_attenuation.x3dv",
    "castle-demo-models-classic/lights_materials/cubes_mesh.wrl",
    "castle-demo-models-classic/animation/simple_tests_interpolation_and_time/"
    "orientation_interpolator_aluminium.wrl",
    "castle-demo-models-classic/animation/simple_tests_interpolation_and_time/IkeaTable.x3dvz",
    "castle-demo-models-classic/x3d/shininess_phong_lighting_effect.x3dv",
    "castle-demo-models-classic/x3d/kings_head_transparent.x3dv",
    "castle-demo-models-classic/x3d/import_export.x3dv",
    "castle-demo-models-classic/x3d/extrusion.x3dv",
    "castle-demo-models-classic/vrml_engine_doc_simple_examples/group_2_lit.wrl",
    # web3d-json-pairs: X3D JSON
    "web3d-json-pairs/arcold.json",
    "web3d-json-pairs/BoxEm.json",
    "web3d-json-pairs/qq3.json",
    "web3d-json-pairs/bubs2.json",
    "web3d-json-pairs/geobubbles.json",
    "web3d-json-pairs/mirror.json",
)


@dataclass(frozen=True)
class Conversion:
    """One scene file converted to each of :data:`FORMATS`.

    ``source``: the file where it lies; ``staged``: its path under the
    scratch folder's ``in/`` (see the module docstring)."""

    id: str
    what: str
    source: Path
    staged: str
    needs_corpus: bool
    method: str = "planar"

    def run(self, scratch: Path) -> Digest:
        target = scratch / "out" / self.method / self.staged
        return convert(scratch / "in" / self.staged, target, self.method, scratch)


def cases(root: Path, corpus: Path | None) -> list[Conversion]:
    """The example scenes of the repository at ``root``, then the same with
    ``--method volume``, then the corpus scenes (none when ``corpus`` is None)."""
    examples = sorted(path for path in (root / "examples" / "scenes").iterdir() if path.is_file())
    found = [
        Conversion(
            f"convert{'' if method == 'planar' else '-' + method}/examples/{path.name}",
            f"bundled example scene{'' if method == 'planar' else ', --method ' + method}",
            path,
            f"examples/scenes/{path.name}",
            False,
            method,
        )
        for method in ("planar", "volume")
        for path in examples
    ]
    return found + [
        Conversion(f"convert/corpus/{name}", "corpus scene", corpus / name, f"corpus/{name}", True)
        for name in CORPUS
        if corpus is not None
    ]


def corpus_ids() -> list[str]:
    """The ids of the corpus cases, known without the corpus."""
    return [f"convert/corpus/{name}" for name in CORPUS]


def stage(root: Path, corpus: Path | None, scratch: Path) -> None:
    """Copy the example scenes and each corpus collection used into ``scratch/in``."""
    shutil.copytree(root / "examples" / "scenes", scratch / "in" / "examples" / "scenes")
    if corpus is not None:
        for collection in sorted({name.split("/")[0] for name in CORPUS}):
            shutil.copytree(corpus / collection, scratch / "in" / "corpus" / collection)


def convert(source: Path, target: Path, method: str, scratch: Path) -> Digest:
    """``source`` with its shadows (by ``method``, as ``convert --method``),
    written to ``target`` with each suffix of :data:`FORMATS`: each file's
    sha256 and size, and the notes' (an error is the result). A note naming
    a file under ``scratch`` names it as ``<scratch>/...``."""
    import shadowgeo

    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        scene = shadowgeo.load(source)
        result = shadowgeo.add_shadows(scene, method=method)
        files = {}
        for suffix in FORMATS:
            out = target.with_name(target.name + suffix)
            shadowgeo.save(result, out)
            files[suffix] = out.read_bytes()
    except Exception as exception:  # the error is the golden result of this case
        failed = error(exception)
        failed.record["input_sha256"] = sha256(source.read_bytes())
        return failed
    # the notes (what the reader skipped, the shadows' notes) as the command prints them
    notes = "\n".join(result.warnings).replace(str(scratch), "<scratch>")
    record = {
        "kind": "conversion",
        "input_sha256": sha256(source.read_bytes()),
        "notes_sha256": sha256(notes.encode()),
        "outputs": {suffix: sha256(data) for suffix, data in files.items()},
        "sizes": {suffix: len(data) for suffix, data in files.items()},
        "counts": {
            "shadow_shapes": sum(
                1 for shape in result.shapes if shape.role in ("shadow", "volume")
            ),
            "lights": len(scene.lights),
            "notes": len(result.warnings),
        },
    }
    kept = {target.name + suffix: data for suffix, data in files.items()}
    return Digest(record, files={**kept, "notes.txt": notes.encode()})
