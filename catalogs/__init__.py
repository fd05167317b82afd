"""Pipe and fitting catalogs as CSV data files, one per standard (installed as ``asbuilt.catalogs``).

Read them with :func:`asbuilt.catalog.load_catalog`; the file format and the sources of every
table are described in ``docs/catalogs.md``.
"""
