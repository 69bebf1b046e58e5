"""The gallery scripts of docs/examples run to their final assertion, each in an empty working directory
that it leaves empty (they write only into temporary directories), and leave the figures of their page
as matplotlib Figures in their globals (what the gallery's scraper collects), which render."""

import io
import runpy
from pathlib import Path

import pytest
from matplotlib.figure import Figure

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"
SCRIPTS = ("plot_quarter_ball.py", "plot_cyclic_loading.py", "plot_creep.py", "plot_adaptive.py")


@pytest.mark.parametrize("script", SCRIPTS)
def test_gallery_script(script, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace = runpy.run_path(str(EXAMPLES / script), run_name="__main__")
    assert list(tmp_path.iterdir()) == []
    figures = [value for value in namespace.values() if isinstance(value, Figure)]
    assert figures, f"{script} leaves no figure for its page"
    for figure in figures:
        figure.savefig(io.BytesIO(), format="png", dpi=50)
