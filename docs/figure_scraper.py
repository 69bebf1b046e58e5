"""The sphinx-gallery image scraper of the vpcontact gallery.

:mod:`vpcontact.results.plots` makes its figures as ``matplotlib.figure.Figure`` objects without pyplot, which
sphinx-gallery's matplotlib scraper (it asks pyplot for its open figures) does not see. This scraper
shows, after each code block of an example, every Figure the block left in the example's global
names that no earlier block showed: a name bound to a Figure, a Figure in a list, tuple or dict bound
to a name (one level deep), and the block's last expression when it is a Figure. Named in conf.py as
``"figure_scraper.scrape"`` (a module, so that Sphinx can pickle the configuration).
"""

import weakref

from matplotlib.figure import Figure
from sphinx_gallery.scrapers import figure_rst

_shown: "weakref.WeakSet[Figure]" = weakref.WeakSet()
"""Figures already on a page (a new example's Figures are new objects)."""


def _figures(value) -> list[Figure]:
    """The Figures a global name holds: itself, or the items of a list, tuple or dict."""
    if isinstance(value, Figure):
        return [value]
    if isinstance(value, dict):
        value = list(value.values())
    if isinstance(value, (list, tuple)):
        return [item for item in value if isinstance(item, Figure)]
    return []


def scrape(block, block_vars, gallery_conf, **kwargs) -> str:
    """Save the block's new Figures to the gallery's image paths; return their reST."""
    new = []
    for value in block_vars["example_globals"].values():
        for figure in _figures(value):
            if figure not in _shown and all(figure is not seen for seen in new):
                new.append(figure)
    paths = []
    for figure, path in zip(new, block_vars["image_path_iterator"]):
        figure.savefig(path, **kwargs)
        _shown.add(figure)
        paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
