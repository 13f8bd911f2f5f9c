"""X3D in all its encodings: XML (``.x3d``, ``.x3dz``), JSON (``.x3dj``),
ClassicVRML (``.x3dv``) and VRML 97 (``.wrl``).

Every encoding becomes the same lxml element tree: :mod:`.parse` parses XML,
hands JSON to :mod:`.json` and ClassicVRML / VRML 97 text to
:mod:`.classic_read` (tokens in :mod:`.classic_tokens`); :mod:`.read` reads
that tree whatever the encoding, with :mod:`.fields` (field values),
:mod:`.geometry` and :mod:`.extrusion` (geometry nodes), :mod:`.lights`,
:mod:`.proto` and :mod:`.extern` (PROTO, EXTERNPROTO), :mod:`.inline`
(Inline files) and :mod:`.script` (what a Script may change). :mod:`.write`
writes the tree back in the encoding the output's extension names
(:mod:`.classic_write`, :mod:`.json`), with :mod:`.numbers` (number text),
:mod:`.layout` (indentation) and :mod:`.urls` (relative urls for the output's
folder). :mod:`.tables` is what they know of X3D 4.0 (field types and
defaults, default containerFields), generated from its schemas by
``tools/x3d_tables.py``.

This package imports nothing itself, so importing one module loads only what
that module needs.
"""

__all__: list[str] = []
