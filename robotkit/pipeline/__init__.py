"""The doit machinery of a build: task dicts (``tasks``), their actions (``actions``), the run
through doit's API (``runner``), all-or-nothing publication (``publish``), the no-op fast path
(``stamp``), the build's warnings (``buildwarn``), the progress line and Dask offloading.

Kept light: the CLI imports ``pipeline.stamp`` before anything heavy."""
