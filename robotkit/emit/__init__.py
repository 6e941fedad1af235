"""Emitters: a finalized Robot -> the text of one output file.

Each emitter module declares its output formats at its bottom (``FORMATS``: name, render
function, path, templates, what it reads, options; :class:`robotkit.emit.formats.Format`);
:data:`robotkit.emit.registry.FORMATS` merges them, as trimesh's ``exchange`` loaders are merged.  The doit tasks and
the tests loop over this registry.  An emitter reads only the resolved model, never the recipe.
"""
