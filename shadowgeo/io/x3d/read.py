"""Read X3D (XML ``.x3d``, JSON ``.x3dj`` / ``.json``, ClassicVRML ``.x3dv``,
VRML 97 ``.wrl``; gzip ``.x3dz``, ``.x3dvz``, ``.wrz``, ``*.gz``) into a
:class:`~shadowgeo.Scene`.

Every encoding is parsed into the XML encoding's element tree
(:mod:`.parse`, :mod:`.json`, :mod:`.classic_read`), which this one
reader reads.

Rules the reader follows, where X3D leaves a choice:

- **One Shape per rendered instance.** A Shape reached twice through USE
  gives two :class:`~shadowgeo.Shape` objects (sharing their vertex and face
  arrays: do not modify those in place).
- **Names.** ``Shape.name`` is the Shape's DEF, else its geometry's DEF, else
  the DEF of the nearest named ancestor (Transform, Group, Inline, ...).
- **Transforms.** ``T C R SR S -SR -C`` (the spec's order); MatrixTransform's
  16 numbers are row-major with the translation in the last row (Castle Game
  Engine and VRML 97 convention), so the column-vector matrix is their transpose.
- **Choices.** Switch shows child ``whichChoice`` (none for -1); LOD shows
  level 0, the most detailed; Billboard keeps its children unrotated (it faces
  the viewer, and there is none); Collision's ``proxy`` is not rendered. A USE
  goes to its node type's default containerField unless it names one (as X3D
  browsers do), not to the DEF's. A DEF name given again rebinds the USEs
  after it (with a warning).
- **Defaults** are X3D 4.0's (from the schema), except that files declaring
  version 3.x get 3.x SpotLight defaults (beamWidth pi/2, cutOffAngle pi/4).
- **Light scope.** A light with ``global`` false (DirectionalLight's
  default) lights only its parent grouping node's descendants (an Inline's
  for one at the top of an inlined file): its ``SceneLight.scope`` is that
  node instance's id, in the ``Shape.scopes`` of the shapes under it. A
  light reached twice through USE is two lights, each scoped where it is
  reached; one at the top of the scene's own file lights everything. The
  shapes of an inlined glTF lie in the Inline's scope like any other.
- **Viewpoints** of the scene's own file (not of its Inlines, as X3D binds
  none of those first) go to ``Scene.viewpoints`` in world coordinates, in
  the order they are reached.
- **Units.** ``<unit category="length">`` sets ``Scene.meters_per_unit``;
  ``category="angle"`` scales every angle field.
- **Prototypes.** A ProtoInstance is its ProtoBody's first node, copied with
  the instance's field values, passed on through ``IS`` to nested instances
  (:mod:`.proto`); an ExternProtoDeclare is followed to a PROTO in a local
  file under Inline's rules (:mod:`.extern`), whose urls are then taken
  from that file's folder.
- **Scripts** are not run: one that builds geometry, or any Script of a scene
  with no geometry, gets one note saying so (:mod:`.script`).
- **Skipped, with a warning in** ``Scene.warnings`` naming file, line and
  node, where X3D browsers are lenient: nodes shadowgeo does not model or does
  not know (scripts, sensors, interpolators, routes, text, lines, points,
  textures), missing textures, empty geometry, a USE naming no DEF or a node
  of another type, a field value that cannot be read (the field takes its
  default), geometry that cannot be built (indices out of range, counts that
  do not fit: that Shape), Inline and EXTERNPROTO files that are missing,
  remote (never fetched), outside the scene's folder (never read), unreadable
  or not X3D/glTF, and EXTERNPROTO files with no such PROTO. Metadata and
  WorldInfo are skipped silently.
- **Refused with a SceneError** (what cannot be read as a scene at all):
  malformed XML or JSON, DOCTYPE entity declarations, a root that is not X3D,
  DEF/USE, prototype, EXTERNPROTO and Inline cycles, expansion bombs (DEF/USE,
  Inline and prototypes beyond 2 million nodes, 500,000 grouping nodes and
  Shapes to walk or the triangle budget, all estimated before the walk by
  :mod:`.budget`; prototypes beyond 10,000 copies), transforms that
  overflow.
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
import types
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from lxml import etree

from ... import limits
from ...errors import GeometryError, SceneError
from ...scene import Material, Scene, SceneLight, Shape
from ...scene.model import MARK, Placement, Viewpoint, axis_angle
from ...tolerance import Tolerance
from .. import file_problem, float_triple
from . import parse as x3d_parse
from .budget import Estimates, Expansion, expansion, flat_expansion, past_budget
from .fields import Context, Element, Tree, local_name, parse, rotation_matrix
from .geometry import GEOMETRY, UNMODELLED_GEOMETRY, Instance, Mesh, Primitive, geometry
from .inline import URL_SCHEME, load_inline
from .lights import LIGHTS, material, scene_light
from .numbers import Splicer
from .proto import Prototypes
from .script import script_note
from .tables import DEFAULTS

__all__ = ["GROUPS", "MAX_NODES", "REASONS", "RENDERED_FIELDS", "SILENT", "TEXTURES", "read"]

GROUPS = {"Group", "StaticGroup", "Collision", "Anchor", "Billboard", "CADAssembly", "CADLayer"}
GROUPS |= {"CADPart", "CADFace", "Layer", "LayerSet", "Transform", "MatrixTransform"}
GROUPS |= {"Switch", "LOD"}
RENDERED_FIELDS = {"children", "choice", "level", "layers", "shape"}
SILENT = {"WorldInfo", "ProtoDeclare", "ExternProtoDeclare", "IS", "connect", "field"}
TEXTURES = {"ImageTexture", "MovieTexture", "ImageCubeMapTexture", "ImageTexture3D"}
# Node instances visited at most: DEF/USE nesting can expand exponentially.
MAX_NODES = limits.MAX_NODES  # every budget is stated in shadowgeo.limits
# Python frames one level of grouping nodes may take in the traversal (node,
# children, an Inline's reader, a prototype's copy), with room to spare.
_FRAMES_PER_LEVEL = 8
# Why nodes of a kind are skipped, for the warnings.
REASONS = [
    (("Sensor", "Interpolator", "Script", "ROUTE", "Trigger", "Sequencer", "Filter", "Follower",
      "Chaser", "Damper", "HAnim", "Proto", "IMPORT", "EXPORT"),
     "animation and behaviour are not modelled (the scene is taken as it is at load time)"),
    (("NavigationInfo", "Background", "Fog", "Sound", "AudioClip", "Environment",
      "OrthoViewpoint", "ViewpointGroup", "TextureBackground"),
     "view, sound and environment settings cast no shadow"),
]  # fmt: skip


class _Reader:
    def __init__(
        self, root_folder: Path, warnings: list[str], max_triangles: int | None = None
    ) -> None:
        self.root_folder = root_folder
        self.warnings = warnings
        self.instances: list[Instance] = []
        self.lights: list[SceneLight] = []
        self.viewpoints: list[Viewpoint] = []  # the top document's, in traversal order
        self.skipped: dict[tuple[str, str], list[Any]] = {}  # (tag, why) -> [first place, count]
        self.textures_seen: set[Element] = set()
        self.geometry_cache: dict[Element, Mesh | Primitive | None] = {}
        # what each node's own fields say, read once: a DEF'd Transform USEd
        # a million times through a chain is one element
        self.local_matrices: dict[Element, np.ndarray] = {}
        self.hidden: dict[Element, bool] = {}  # visible='false'
        self.rendered: dict[Element, list[Element]] = {}  # the children drawn
        self.material_cache: dict[Element | None, Material] = {}
        self.inline_stack: list[Path] = []
        self.open_groups: set[int] = set()  # ids of the grouping nodes being traversed
        self.baked: list[str] = []  # DEFs of the enclosing groups of shadows shadowgeo added
        # what the documents and prototype copies read so far expand to, and
        # what each element does (budget)
        self.expanded = Expansion()
        self.estimates = Estimates(
            Expansion(MAX_NODES, limits.MAX_VISITS, max_triangles or limits.MAX_TRIANGLES)
        )
        self.inline_files: dict[Path, Any] = {}  # each Inline file read once: tree or Scene
        self.inlines_read = 0  # X3D Inline instances read (limits.MAX_INLINE_INSTANCES)
        self.top_root: Element | None = None  # the root of the scene's own document
        self.headlight: bool | None = None  # of the top document's first NavigationInfo
        # ids of the grouping node (and Inline) instances being read, outermost
        # first; those holding a non-global light are its scope (SceneLight.scope)
        self.within: tuple[int, ...] = ()
        self.opened = 0  # grouping node instances read so far: the next one's id
        self.scopes: set[int] = set()  # the ids that are some light's scope

    # -- documents ---------------------------------------------------------------
    def document(
        self,
        tree: Tree,
        path: Path,
        matrix: np.ndarray,
        scene: Scene | None = None,
        name: str | None = None,
    ) -> None:
        root = tree.getroot()
        display = str(path)
        context = Context(display, _version(root, display, self.warnings), warnings=self.warnings)
        if scene is not None:  # the scene's own document: its long numbers held as bytes
            self.top_root = root
            scene.numbers = Splicer()
            context.kept, context.kept_root = scene.numbers, root
        self._units(context, root, scene)
        context.defs = _definitions(context, root)
        context.prototypes = Prototypes(root, display, self)
        scenes = [child for child in root if local_name(child) == "Scene"]
        if not scenes:
            raise SceneError("no <Scene> element", path=display, line=root.sourceline)
        self._count(context, scenes[0])
        _refuse_written_past(context, scenes[0])
        self.inline_stack.append(path.resolve())
        try:
            self.children(context, scenes[0], matrix, name)
        finally:
            self.inline_stack.pop()

    def _count(self, context: Context, element: Element, at: Element | None = None) -> None:
        """Add what ``element`` expands to (budget) to what the scene does so
        far, counted over every document and prototype copy read (Inlines and
        prototypes used again multiply too); refuse the scene, before it is
        walked, beyond its budgets of nodes, visits or triangles, naming the
        innermost node too big (else ``at``, else ``element``)."""
        if element.get("USE") is None and not _USES_INSIDE(element):
            # nothing to expand: counted by libxml2, not a Python call each node
            found = flat_expansion(context, element)
        else:
            found = expansion(context, element, self.estimates)
        self.expanded = self.expanded + found
        budget, first_over = self.estimates.budget, self.estimates.first_over

        def named(measure: str) -> Element:
            if at is not None:  # a prototype's copy: the instance (its DEFs are renamed)
                return at
            return first_over.get(measure, element)

        # memory first: the measure a bomb with geometry in it would fill
        if self.expanded.triangles > budget.triangles:
            node = named("triangles")
            limits.check_expansion(
                self.expanded.triangles,
                context.file_of(node),
                context.describe(node),
                node.sourceline,
                budget.triangles,
            )
        if self.expanded.visits > budget.visits:
            raise context.error(
                named("visits"),
                f"the scene expands (through DEF/USE, Inline or prototypes) to "
                f"{self.expanded.visits:,} grouping nodes and Shapes to walk, more than "
                f"{budget.visits:,} (shadowgeo.limits.MAX_VISITS); refused before the walk",
            )
        if self.expanded.nodes > budget.nodes:
            raise context.error(
                named("nodes"),
                f"the scene expands (through DEF/USE, Inline or prototypes) to more than "
                f"{MAX_NODES} nodes",
            )

    def _units(self, context: Context, root: Element, scene: Scene | None) -> None:
        for unit in (e for e in root.iter() if local_name(e) == "unit"):
            category, factor = unit.get("category"), unit.get("conversionFactor", "")
            try:
                value = float(factor)
            except ValueError:
                value = float("nan")
            if not value > 0 or category not in ("angle", "length", "force", "mass"):
                context.warn(
                    unit, f"unit category={category!r} conversionFactor={factor!r} ignored"
                )
            elif category == "angle":
                context.angle_factor = value
            elif category == "length" and scene is not None:
                scene.meters_per_unit = value

    # -- traversal ---------------------------------------------------------------
    def children(
        self, context: Context, element: Element, matrix: np.ndarray, name: str | None
    ) -> None:
        tag = local_name(element)
        if element not in self.rendered:
            self.rendered[element] = [
                child
                for child in element
                if local_name(child) and child.get("containerField", "children") in RENDERED_FIELDS
            ]
        rendered = self.rendered[element]
        if tag == "Switch":
            choice = context.field(element, "whichChoice")
            rendered = [rendered[choice]] if 0 <= choice < len(rendered) else []
        elif tag == "LOD":
            if len(rendered) > 1:
                context.warn(element, f"LOD: level 0 of {len(rendered)} used")
            rendered = rendered[:1]
        for child in rendered:
            self.node(context, child, matrix, name)

    def node(
        self, context: Context, written: Element, matrix: np.ndarray, name: str | None
    ) -> None:
        element = self._entered(context, written)
        if element is None:  # a prototype instance that could not be expanded
            return
        tag = local_name(element)
        name = _public(written.get("DEF") or element.get("DEF")) or name
        if self._hidden(context, element, tag):
            context.warn(element, "visible='false': skipped")
            return
        if tag in GROUPS:
            self.group(context, element, tag, matrix, name)
        elif tag == "Shape":
            self.shape(context, element, matrix, name)
        elif tag in LIGHTS:
            self.light(context, element, matrix)
        elif tag == "Inline":
            with self._scope():  # the inlined scene's own lights light it
                load_inline(self, context, element, matrix, name)
        elif tag in ("NavigationInfo", "Viewpoint") and len(self.inline_stack) == 1:
            self.bindable(context, element, tag, matrix)
        elif tag == "Viewpoint":
            self._skip(context, element, tag, "a Viewpoint of an inlined file (X3D binds none)")
        elif tag not in SILENT and not tag.startswith("Metadata"):
            self._skip(context, element, tag, _why(tag))

    def _entered(self, context: Context, written: Element) -> Element | None:
        """The node ``written`` stands for (a USE's DEF, a prototype's copy), counted
        and checked not to be a group it is inside of."""
        element = context.node(written)
        if element is None:
            return None
        if local_name(written) == "ProtoInstance":
            self._count(context, element, written)  # the copy of the prototype's body
        if id(element) in self.open_groups:
            raise context.error(
                written, f"DEF/USE cycle: '{written.get('USE')}' is used inside itself"
            )
        return element

    def _hidden(self, context: Context, element: Element, tag: str) -> bool:
        """Whether the node says ``visible='false'`` (asked once per element)."""
        if element not in self.hidden:
            self.hidden[element] = "visible" in DEFAULTS.get(tag, {}) and not context.field(
                element, "visible"
            )
        return self.hidden[element]

    def group(
        self, context: Context, element: Element, tag: str, matrix: np.ndarray, name: str | None
    ) -> None:
        """A grouping node: its children under its world matrix, in its own scope."""
        if tag == "Billboard":
            context.warn(element, "Billboard: children kept unrotated (no viewer)")
        if element not in self.local_matrices:
            self.local_matrices[element] = _local_matrix(context, element, tag)
        with np.errstate(over="ignore", invalid="ignore"):
            world = matrix @ self.local_matrices[element]
        if not np.isfinite(world).all():
            raise context.error(element, "the transforms down to here overflow to infinity")
        if len(self.open_groups) >= limits.MAX_NESTING:  # e.g. a prototype inside itself
            raise context.error(
                element,
                f"nodes nested too deeply (grouping nodes more than {limits.MAX_NESTING} "
                "deep through DEF/USE, prototypes or Inline; shadowgeo.limits.MAX_NESTING)",
            )
        self.open_groups.add(id(element))  # the element stays alive meanwhile
        baked = MARK in (element.get("class") or "").split()
        if baked:
            self.baked.append(element.get("DEF") or "shadows")
        try:
            with self._scope():
                self.children(context, element, world, name)
        finally:
            self.open_groups.discard(id(element))
            if baked:
                self.baked.pop()

    def light(self, context: Context, element: Element, matrix: np.ndarray) -> None:
        """A light node, scoped to its group unless global, placed for a writer."""
        if len(self.lights) >= limits.MAX_LIGHTS:
            raise context.error(element, limits.lights_message(len(self.lights) + 1))
        light = scene_light(context, element, matrix)
        if light is None:
            return
        if not light.global_ and self.within:  # at the top of the scene: everything
            light.scope = self.within[-1]
            self.scopes.add(light.scope)
        tree = element.getroottree()
        if tree.getroot() is self.top_root:  # a writer of this document finds it
            light.node = tree.getpath(element)
            group = element.getparent()
            if light.scope is not None and _holds_added(group):
                light.scope_group = Placement(tree.getpath(group), matrix.copy())
        self.lights.append(light)

    def bindable(self, context: Context, element: Element, tag: str, matrix: np.ndarray) -> None:
        """A NavigationInfo or Viewpoint of the top file."""
        if tag == "Viewpoint":
            self.viewpoints.append(_viewpoint(context, element, matrix))
        elif self.headlight is None:  # the first NavigationInfo is the one a browser binds
            self.headlight = bool(context.field(element, "headlight"))

    @contextlib.contextmanager
    def _scope(self) -> Iterator[None]:
        """Read a grouping node instance (or an Inline) inside: its id is the
        scope of the non-global lights among its children."""
        outer = self.within
        self.within = (*outer, self.opened)
        self.opened += 1
        try:
            yield
        finally:
            self.within = outer

    def _skip(
        self, context: Context, element: Element, tag: str, why: str = "not modelled"
    ) -> None:
        entry = self.skipped.setdefault((tag, why), [context.where(element), 0])
        entry[1] += 1

    def shape(
        self, context: Context, element: Element, matrix: np.ndarray, name: str | None
    ) -> None:
        geometry_nodes = context.children(element, GEOMETRY | UNMODELLED_GEOMETRY)
        if not geometry_nodes:
            context.warn(element, "Shape without geometry; skipped")
            return
        node = geometry_nodes[0]
        tag = local_name(node)
        if tag in UNMODELLED_GEOMETRY:
            self._skip(context, node, tag, "geometry not modelled (no area or not supported)")
            return
        built = self._built(context, node)
        if built is None:
            return
        appearances = context.children(element, {"Appearance"})
        appearance = appearances[0] if appearances else None
        if appearance not in self.material_cache:
            self.material_cache[appearance] = material(context, appearance)
            if appearance is not None:
                self._textures(context, appearance)
        self.instances.append(
            Instance(
                built,
                matrix,
                self.material_cache[appearance],
                _public(element.get("DEF") or node.get("DEF")) or name,
                f"{os.path.basename(context.file_of(node))} line {node.sourceline}, "
                f"{context.describe(node)}",
                *self._added_role(element),
                casts_shadow=_casts_shadow(context, element, appearance),
                within=self.within,
            )
        )

    def _built(self, context: Context, node: Element) -> Mesh | Primitive | None:
        """A geometry node's mesh or primitive (built once), None when bad or empty."""
        if node not in self.geometry_cache:
            try:
                built = geometry(context, node)
            except (SceneError, GeometryError) as error:  # a bad index, count, size, ...
                self.warnings.append(f"{error}; the Shape is skipped")
                self.geometry_cache[node] = None
                return None
            empty = isinstance(built, Mesh) and (len(built.faces) == 0 or len(built.vertices) == 0)
            for note in getattr(built, "notes", []):
                context.warn(node, note)
            if empty:
                context.warn(node, "empty geometry (no triangles); skipped")
            self.geometry_cache[node] = None if empty else built
        return self.geometry_cache[node]

    def _added_role(self, element: Element) -> tuple[str, str | None]:
        """Shapes in a group of shadows shadowgeo added read back as role
        "shadow" (or "volume"), not as geometry that casts."""
        if not self.baked:
            return "geometry", None
        marks = (element.get("class") or "").split()
        role = next((r for r in ("volume", "ground") if f"{MARK}-{r}" in marks), "shadow")
        return role, self.baked[-1]

    def _textures(self, context: Context, appearance: Element) -> None:
        for texture in (e for e in appearance.iter() if local_name(e) in TEXTURES):
            texture = context.resolve(texture)
            if texture is None or texture in self.textures_seen:
                continue
            self.textures_seen.add(texture)
            self._texture(context, texture)

    def _texture(self, context: Context, texture: Element) -> None:
        """A note on one texture: not found (and why), else skipped as not modelled."""
        urls = [u for u in context.field(texture, "url", "MFString") if u]
        folder = Path(context.file_of(texture)).resolve().parent
        local = [(folder / u).resolve() for u in urls if not URL_SCHEME.match(u)]
        # only files inside the scene's folder count (nothing outside is looked at)
        inside = [path for path in local if path.is_relative_to(self.root_folder)]
        problems = [file_problem(path) for path in inside]
        if urls and None not in problems:
            # why a url cannot even be looked up (a name too long, ...) is said
            why = sorted({p for p in problems if p not in (None, "not found", "not a file")})
            reason = f" ({'; '.join(why)})" if why else ""
            context.warn(texture, f"texture not found: {', '.join(urls[:3])}{reason}")
        else:
            self._skip(context, texture, local_name(texture), "textures not modelled")

    # -- result ------------------------------------------------------------------
    def scripts(self, root: Element, path: str) -> None:
        """One note for a Script that builds geometry (:mod:`.script`), in
        place of the usual note on skipped Scripts."""
        has_geometry = any(instance.role == "geometry" for instance in self.instances)
        note = script_note(root, path, has_geometry)
        if note is not None:
            self.skipped = {key: entry for key, entry in self.skipped.items() if key[0] != "Script"}
            self.warnings.append(note)

    def finish(self, scene: Scene, tolerance: Tolerance | None, chord: float | None) -> None:
        for (_, why), (where, count) in self.skipped.items():
            more = f" ({count} such nodes)" if count > 1 else ""
            self.warnings.append(f"{where}: skipped, {why}{more}")
        tolerance = self._tolerance(tolerance, chord)
        tessellated: dict[tuple[Any, ...], Mesh] = {}
        scopes: dict[tuple[int, ...], frozenset[int]] = {}  # shared by a group's shapes
        stretches: dict[bytes, float] = {}  # by linear part: shapes side by side share one
        budget, built_so_far = self.estimates.budget.triangles, 0
        for instance in self.instances:
            if instance.within not in scopes:
                scopes[instance.within] = frozenset(self.scopes.intersection(instance.within))
            built = instance.geometry
            if isinstance(built, Primitive):
                stretch = _stretch(instance.transform[:3, :3], stretches)
                local_chord = tolerance.chord_length / stretch
                # equal primitives share one tessellation (and its arrays)
                key = (built.key, None if built.kind == "Box" else local_chord)
                if key not in tessellated:
                    tessellated[key] = built.tessellate(local_chord)
                    for note in tessellated[key].notes:
                        self.warnings.append(f"{instance.source}: {note}")
                built = tessellated[key]
            # the estimate counted a curved primitive at its fewest triangles:
            # the exact count, shape by shape, stops a scene at its budget
            built_so_far += len(built.faces)
            limits.check_triangles(built_so_far, instance.source, budget)
            scene.shapes.append(
                Shape(
                    built.vertices,
                    built.faces,
                    transform=instance.transform,
                    material=instance.material,
                    name=instance.name,
                    solid=instance.geometry.solid,
                    source=instance.source,
                    role=instance.role,
                    group=instance.group,
                    casts_shadow=instance.casts_shadow,
                    crease_angle=built.crease_angle,
                    scopes=scopes[instance.within],
                )
            )
        scene.lights.extend(self.lights)
        scene.viewpoints.extend(self.viewpoints)
        scene.headlight = True if self.headlight is None else self.headlight

    def _tolerance(self, tolerance: Tolerance | None, chord: float | None) -> Tolerance:
        settings = {} if chord is None else {"chord": float(chord)}
        if tolerance is not None:
            return tolerance.with_settings(**settings)
        # Primitives are measured on a coarse tessellation (1% of their size):
        # their bounding cube would overstate a turned sphere's extent.
        points, coarse = [], {}
        for instance in self.instances:
            built, transform = instance.geometry, instance.transform
            if isinstance(built, Primitive):
                if built.key not in coarse:
                    coarse[built.key] = built.tessellate(0.01 * built.radius).vertices
                local = coarse[built.key]
            else:
                local = built.vertices
            if not np.array_equal(transform, _IDENTITY):
                local = local @ transform[:3, :3].T + transform[:3, 3]
            points.append(local)
        return Tolerance.for_points(*points, **settings)


_IDENTITY = np.eye(4)


def _stretch(linear: np.ndarray, known: dict[bytes, float]) -> float:
    """The most ``linear`` (3, 3) lengthens a vector (its largest singular
    value; 1 for a degenerate one), remembered in ``known`` by its bytes."""
    key = linear.tobytes()
    if key not in known:
        known[key] = float(np.linalg.norm(linear, 2)) or 1.0
    return known[key]


def _casts_shadow(context: Context, shape: Element, appearance: Element | None) -> bool:
    """False when the author said the Shape casts no shadow: X3D 4's
    ``Shape castShadow="false"`` or Castle Game Engine's ``Appearance
    shadowCaster="false"`` (an extension: read only where written)."""
    if not context.field(shape, "castShadow"):
        return False
    written = None if appearance is None else appearance.get("shadowCaster")
    if written is None:
        return True
    try:
        return bool(parse(written, "SFBool"))
    except ValueError as problem:
        context.warn_once(
            appearance, f"field shadowCaster: '{written[:40]}' {problem}; TRUE is used"
        )
        return True


def _public(name: str | None) -> str | None:
    """A DEF name as the file writes it (prototype copies prefix theirs with 'N#')."""
    if not name or "#" not in name:
        return name
    return name.split("#", 1)[1] if re.match(r"\d+#", name) else name


def _viewpoint(context: Context, element: Element, matrix: np.ndarray) -> Viewpoint:
    """A Viewpoint in world coordinates (the transforms' scale does not
    change its field of view)."""
    rotation = rotation_matrix(context.field(element, "orientation"))
    position = matrix[:3, :3] @ context.field(element, "position") + matrix[:3, 3]
    field_of_view = context.field(element, "fieldOfView")
    if not 0 < field_of_view < np.pi:
        context.warn_once(element, f"fieldOfView {field_of_view:g} is not in (0, pi); pi/4 used")
        field_of_view = np.pi / 4
    return Viewpoint(
        float_triple(position),
        axis_angle(matrix[:3, :3] @ rotation),
        float(field_of_view),
        context.field(element, "description"),
        _public(element.get("DEF")),
    )


def _refuse_written_past(context: Context, scene: Element) -> None:
    """Refuse, before the walk, a document holding more light nodes than the
    scene may have lights, or more ProtoInstances than prototypes may expand:
    the walk would refuse it after reading that many (10,000 in seconds)."""
    light = past_budget(scene, LIGHTS, limits.MAX_LIGHTS)
    if light is not None:
        raise context.error(
            light,
            f"more than {limits.MAX_LIGHTS:,} lights (the file holds more light nodes than "
            "that; refused before it is read; shadowgeo.limits.MAX_LIGHTS)",
        )
    instance = past_budget(scene, {"ProtoInstance"}, limits.MAX_PROTO_EXPANSIONS)
    if instance is not None:
        raise context.error(
            instance,
            f"more than {limits.MAX_PROTO_EXPANSIONS:,} prototype copies (the file holds more "
            "ProtoInstance nodes than that; refused before they are expanded; "
            "shadowgeo.limits.MAX_PROTO_EXPANSIONS)",
        )


def _why(tag: str) -> str:
    for words, reason in REASONS:
        if any(word in tag for word in words):
            return reason
    return "not modelled"


# (XPath, evaluated by libxml2 once per document or prototype copy counted:
# 50,000 nodes in a few ms, not a Python call per node)
_USES_INSIDE = etree.XPath("boolean(descendant::*[@USE])")


def _version(root: Element, display: str, warnings: list[str]) -> tuple[int, int]:
    text = root.get("version", "4.0")
    match = re.fullmatch(r"\s*(\d+)\.(\d+)\s*", text)
    if not match:
        warnings.append(f"{display} line {root.sourceline}, X3D: version {text!r}; 4.0 assumed")
        return (4, 0)
    return int(match.group(1)), int(match.group(2))


def _definitions(context: Context, root: Element) -> dict[str, list[Element]]:
    """DEF name -> elements in document order, outside prototype declarations
    (their names are local)."""
    defs: dict[str, list[Element]] = {}
    for element in root.iter():
        if not isinstance(element.tag, str) or element.get("DEF") is None:
            continue
        if any(
            local_name(a) in ("ProtoDeclare", "ExternProtoDeclare") for a in element.iterancestors()
        ):
            continue
        name = element.get("DEF")
        if name in defs:
            context.warn(element, f"DEF '{name}' is defined again; later USEs refer to this one")
        defs.setdefault(name, []).append(element)
    return defs


# The fields of a Transform other than its translation: where none is given,
# the local matrix is a translation.
_TURNING_FIELDS = ("rotation", "scale", "scaleOrientation", "center")


def _local_matrix(context: Context, element: Element, tag: str) -> np.ndarray:
    """4x4 local-to-parent matrix of a grouping node (identity for plain groups)."""
    local = np.eye(4)
    if tag == "MatrixTransform":
        local = context.field(element, "matrix").reshape(4, 4).T.copy()
    elif tag in ("Transform", "CADPart"):
        if all(element.get(name) is None for name in _TURNING_FIELDS):
            # (the defaults' matrices are exact identities: the same numbers)
            local[:3, 3] = context.field(element, "translation")
            return local
        names = ("translation", "rotation", "scale", "scaleOrientation", "center")
        field = {name: context.field(element, name) for name in names}
        orientation = rotation_matrix(field["scaleOrientation"])
        linear = rotation_matrix(field["rotation"]) @ orientation
        linear = linear @ np.diag(field["scale"]) @ orientation.T
        local[:3, :3] = linear
        center = field["center"]
        local[:3, 3] = field["translation"] + center - linear @ center
    return local


@contextlib.contextmanager
def _stack_for_nesting() -> Iterator[None]:
    """Let Python's recursion limit hold :data:`~shadowgeo.limits.MAX_NESTING`
    grouping nodes (a few frames each) above the caller's own stack while a
    scene is walked, so that the budget, not the limit, stops a deep scene:
    met first inside numpy, the limit can surface as another error. The
    limit is put back afterwards unless something else changed it meanwhile
    (another thread reading a deeper scene)."""
    depth = 0
    frame: types.FrameType | None = sys._getframe()
    while frame is not None:
        depth, frame = depth + 1, frame.f_back
    before = sys.getrecursionlimit()
    needed = depth + _FRAMES_PER_LEVEL * limits.MAX_NESTING + 200
    if before >= needed:
        yield
        return
    sys.setrecursionlimit(needed)
    try:
        yield
    finally:
        if sys.getrecursionlimit() == needed:
            sys.setrecursionlimit(before)


def read(
    path: str | os.PathLike[str],
    *,
    tolerance: Tolerance | None = None,
    chord: float | None = None,
    root: str | os.PathLike[str] | None = None,
    max_triangles: int | None = None,
) -> Scene:
    """Read an X3D file: XML (``.x3d``), JSON (``.x3dj``, ``.json``), ClassicVRML
    (``.x3dv``) or VRML 97 (``.wrl``), the XML and Classic ones also gzip-compressed.

    Parameters
    ----------
    path : str or Path
    tolerance : Tolerance, optional
        Scene tolerance; by default :meth:`Tolerance.for_points` over the
        scene's geometry in world coordinates.
    chord : float, optional
        Tessellation tolerance relative to the scene size (overrides
        ``tolerance.chord``): Box, Sphere, Cone and Cylinder deviate from
        their true surface by at most ``Tolerance.chord_length``.
    root : str or Path, optional
        The folder that Inlines and textures may not leave (default: the
        file's own folder). Name a folder above it for a trusted scene whose
        files lie beside its folder, as a converted scene written to another
        folder names them (:mod:`.urls`).
    max_triangles : int, optional
        The triangle (memory) budget, default
        :data:`~shadowgeo.limits.MAX_TRIANGLES`: a scene estimated to pass
        it through DEF/USE, prototypes or Inline is refused before it is
        built (:mod:`.budget`).

    Returns
    -------
    Scene
        ``shapes`` (one per rendered Shape instance), ``lights`` (world
        coordinates), ``warnings``, ``document`` (the parsed lxml tree,
        comments kept) and ``path``.

    Raises
    ------
    SceneError
        The file cannot be read safely or correctly; the message names the
        file, line and node.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "box.x3d"
    >>> _ = path.write_text(
    ...     '<X3D version="4.0"><Scene><Transform translation="0 1 0">'
    ...     '<Shape DEF="crate"><Box/></Shape></Transform>'
    ...     '<PointLight location="0 5 0" shadows="true"/><Viewpoint description="front"/>'
    ...     '<Background/></Scene></X3D>'
    ... )
    >>> scene = read(path)
    >>> [(shape.name, shape.n_faces) for shape in scene.shapes]
    [('crate', 12)]
    >>> scene.bounds.tolist(), scene.lights[0].light.position.tolist()
    ([[-1.0, 0.0, -1.0], [1.0, 2.0, 1.0]], [0.0, 5.0, 0.0])
    >>> scene.viewpoints[0].position, scene.viewpoints[0].description
    ((0.0, 0.0, 10.0), 'front')
    >>> scene.warnings[0].split(": ", 1)[1]
    'skipped, view, sound and environment settings cast no shadow'
    """
    path = Path(path)
    notes: list[str] = []  # what the ClassicVRML parser skipped
    tree = x3d_parse.parse(path, notes)
    scene = Scene(path=str(path), document=tree, warnings=notes)
    folder = path.resolve().parent
    if root is not None:
        folder = Path(root).resolve()
        if not path.resolve().is_relative_to(folder):
            raise SceneError(f"the file is not inside root {folder}", path=str(path))
    reader = _Reader(folder, scene.warnings, max_triangles)
    reader.inline_files[path.resolve()] = tree  # (an EXTERNPROTO naming it reads this tree)
    try:
        with _stack_for_nesting():
            reader.document(tree, path, np.eye(4), scene)
        reader.scripts(tree.getroot(), str(path))
        reader.finish(scene, tolerance, chord)
    except RecursionError:
        message = "nodes nested too deeply (through DEF/USE, prototypes or Inline)"
        raise SceneError(message, path=str(path)) from None
    except GeometryError as problem:  # e.g. transforms that overflow to infinity
        raise SceneError(str(problem), path=str(path)) from None
    return scene


def _holds_added(group: Element | None) -> bool:
    """Whether a writer may add a shape to ``group``, a light's parent: a
    plain grouping node (not a Switch, LOD or Billboard, which would hide or
    turn it) outside every prototype declaration (whose body is copied into
    every instance, so a node added there would be too)."""
    if group is None or local_name(group) not in _PLAIN_GROUPS:
        return False
    node: Element | None = group
    while node is not None:
        if isinstance(node.tag, str) and local_name(node) in _PROTO_TAGS:
            return False
        node = node.getparent()
    return True


_PLAIN_GROUPS = frozenset({"Group", "Transform", "Collision", "Anchor", "StaticGroup"})
_PROTO_TAGS = frozenset({"ProtoDeclare", "ProtoBody", "ExternProtoDeclare"})
