"""The fuzzing campaign's parts; ``python tools/fuzz.py`` runs it.

Inputs and mutators:

* ``inputs``: the encodings, the seed folders, the command lines a mutant
  runs with, the hostile values;
* ``seeds``: the seed files of each encoding;
* ``mutate``: one mutant, by encoding and level, from
  ``mutate_bytes`` (any encoding), ``mutate_structure`` and
  ``mutate_meaning`` (the text encodings), ``mutate_xml`` (X3D XML),
  ``mutate_json`` (X3D JSON, glTF) and ``glb`` (the glb container).

Runs and checks:

* ``converter``: a mutant through ``shadowgeo convert`` or ``info``, checked;
  ``check_output`` (no NaN or inf written) and ``check_area`` (the textbook
  shadow area);
* ``geometry``: random casters, planes and lights through the API, checked
  by ``check_geometry``;
* ``results``: a run's result record and a failure's signature.

The campaign: ``worker`` and ``pool`` (forked workers with time and memory
budgets), ``shrink`` (delta debugging), ``campaign`` (the run, the failures'
folders and the summary), ``resume`` (a stopped campaign gone on with, on
the same commit and plan only).
"""
