"""Figures: every function takes results and returns a matplotlib Figure (or writes an animation);
none computes anything. :mod:`.common` (axes and paths), :mod:`.plan`, :mod:`.motion`, :mod:`.compare`,
:mod:`.paper` (Figs 6-12), :mod:`.atlas`, :mod:`.animation`, :mod:`.closed_loop`."""
