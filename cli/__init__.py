"""The shadowgeo command line (installed as the import package ``shadowgeo_cli``)."""
