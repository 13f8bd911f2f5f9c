"""Golden outputs: a record of what the code makes today, to compare a later commit with.

``python tools/golden.py record OUT.json`` computes every case and writes a
manifest (the commit, and per case the sha256 of each output's bytes, or a
shadow's area and the sha256 of its arrays); ``compare OLD.json`` recomputes
and prints which cases are identical, different or not run.

- :mod:`golden.digest`: results (``Shadow``, ``SurfaceShadow``, volumes,
  silhouettes, sun studies) as areas, counts and array hashes;
- :mod:`golden.conversions`: the bundled example scenes and 30 corpus scenes
  through the converter's library path, to .x3d, .glb and .usda;
- :mod:`golden.geometry`: the benchmark scenes (a city, a terrain under a
  sphere, three test meshes) and the pyramid under a point, a spot and a
  directional light, through the geometry API;
- :mod:`golden.manifest`: running the cases, the manifest, the comparison.
"""
