"""The rendered documentation (Sphinx): it builds with warnings as errors, and the build runs the gallery.

The build reads a temporary copy of docs/ (sphinx-gallery writes its generated pages next to the
sources), with the README it includes and the case files of examples/ the gallery reads
(``../../examples/*.toml`` from docs/examples), and writes the HTML into the same temporary directory:
the source tree is not written to. sphinx-gallery executes every ``docs/examples/plot_*.py`` during the
build, so this is the gallery's test run; an example whose final assertion fails fails the build, and
the test names it.
"""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import vpcontact

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
GENERATED = ("gallery", "sg_execution_times.rst", "_build")
"""What a build writes into a docs folder, left out of the copy."""
PAGES = ("index", "readme", "api/index", "gallery/index", "3d", "accuracy", "adaptivity", "factorizations",
         "heterogeneity", "long-runs", "performance", "reproduce", "viscoplasticity", "architecture",
         "units")


def copy_sources(target: Path) -> Path:
    """docs/, README.md and the case files of examples/ copied into ``target`` in the repository's layout;
    the copy of docs/."""
    shutil.copytree(DOCS, target / "docs", ignore=shutil.ignore_patterns(*GENERATED, "__pycache__"))
    shutil.copy2(REPO / "README.md", target / "README.md")
    shutil.copytree(REPO / "examples", target / "examples", ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    return target / "docs"


def build_html(source: Path, out: Path) -> subprocess.CompletedProcess:
    """``sphinx-build -W --keep-going -b html source out`` in a subprocess, documenting this checkout's
    sources (its src/ first on the path) and with its temporary files under ``out``."""
    temporary = out / "tmp"
    temporary.mkdir(parents=True)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO / "src"), os.environ.get("PYTHONPATH")])),
           "TMPDIR": str(temporary), "MPLBACKEND": "Agg", "NO_COLOR": "1"}
    return subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html", "-d",
                           str(out / "doctrees"), str(source), str(out / "html")],
                          env=env, capture_output=True, text=True, timeout=900, stdin=subprocess.DEVNULL)


def failing_examples(output: str) -> list[str]:
    """The gallery examples sphinx-gallery reports as failed (their file names), from the build's output: as it
    runs them ("... unexpectedly failed to execute correctly") or in its closing summary ("... failed leaving
    traceback"), colours removed (a terminal, or CI=true, gets them)."""
    plain = re.sub(r"\x1b\[[0-9;]*m", "", output)
    return sorted(set(re.findall(r"([\w.-]+\.py) (?:unexpectedly failed to execute correctly|failed leaving traceback)",
                                 plain)))


def check_built(build: subprocess.CompletedProcess) -> None:
    """Fail with the failing examples' names, or else the build's warnings, unless the build succeeded."""
    output = build.stdout + build.stderr
    failed = failing_examples(output)
    if failed:
        errors = re.findall(r"^\s*(\w+(?:Error|Exception)\b.*)$", re.sub(r"\x1b\[[0-9;]*m", "", output),
                            flags=re.MULTILINE)
        raise AssertionError(f"gallery examples failed: {', '.join(failed)}\n" + "\n".join(dict.fromkeys(errors)))
    warnings = [line for line in output.splitlines() if "WARNING" in line or "ERROR" in line]
    shown = "\n".join(warnings or [output[-3000:]])
    assert build.returncode == 0, f"sphinx-build exit status {build.returncode}:\n{shown}"


def tree(folder: Path) -> dict[str, tuple[int, int]]:
    """Every file under ``folder`` with its size and modification time."""
    return {str(path.relative_to(folder)): (path.stat().st_size, path.stat().st_mtime_ns)
            for path in folder.rglob("*") if path.is_file()}


def test_the_docs_build_without_warnings_and_run_the_gallery(tmp_path):
    before = tree(DOCS)
    build = build_html(copy_sources(tmp_path / "src"), tmp_path / "out")
    check_built(build)
    assert tree(DOCS) == before, "the build wrote into the source tree"

    html = tmp_path / "out" / "html"
    api = sorted(f"api/{page.stem}" for page in (DOCS / "api").glob("*.md"))
    for page in (*PAGES, *api):
        assert (html / f"{page}.html").is_file(), page
    # the API pages hold the public API (every name of vpcontact.__all__, where it is defined) and the modules
    # users call, from the docstrings
    reference = "".join((html / f"{page}.html").read_text() for page in api)
    public = [f"vpcontact.{vpcontact.API[name]}.{name}" if name in vpcontact.API else f"vpcontact.{name}"
              for name in vpcontact.__all__]
    modules = [f"module-vpcontact.{name}" for name in ("results.plots", "results.norms", "drivers.studies",
                                                        "laws.contact", "mesh.shapes", "laws.materials",
                                                        "estimate.indicators", "estimate.residual", "adaptivity.cycles",
                                                        "adaptivity.during_run", "adaptivity.transfer",
                                                        "timeloop.companion", "timeloop.time_control", "io.run")]
    for name in (*public, *modules, "vpcontact.results.plots.contact_pressure", "vpcontact.results.norms.differences"):
        assert f'id="{name}"' in reference, f"{name} is not in the API reference (docs/api/)"
    # every example has its page, and the figures it made (our scraper) are on it
    examples = sorted(path.stem for path in (DOCS / "examples").glob("plot_*.py"))
    assert {"plot_paper_example", "plot_hertz", "plot_rho_limit", "plot_user_stiffness_law",
            "plot_punch_cyclic", "plot_adaptive_during_run", "plot_adaptive_time_steps"} <= set(examples)
    for name in examples:
        page = (html / "gallery" / f"{name}.html").read_text()
        figures = sorted((html / "_images").glob(f"sphx_glr_{name}_[0-9][0-9][0-9].png"))
        assert figures, f"{name}: no figure"
        for figure in figures:
            assert figure.stat().st_size > 10_000, figure.name
            assert f"_images/{figure.name}" in page, f"{figure.name} is not on {name}'s page"
    assert "AssertionError" not in (html / "gallery" / "index.html").read_text()


def test_a_failing_example_fails_the_build_and_is_named(tmp_path):
    """The same configuration on a docs folder whose only example fails its final assertion."""
    source = tmp_path / "docs"
    (source / "examples").mkdir(parents=True)
    for name in ("conf.py", "figure_scraper.py", "examples/README.rst"):
        shutil.copy2(DOCS / name, source / name)
    (source / "index.md").write_text("# Gallery\n\n```{toctree}\ngallery/index\n```\n")
    (source / "examples" / "plot_wrong_number.py").write_text(
        '"""\nA wrong number\n==============\n\nIts final assertion fails.\n"""\n\n'
        "# %%\nvalue = 0.5 + 0.25\nassert abs(value - 1) < 1e-12, f'{value} is not 1'\n")
    build = build_html(source, tmp_path / "out")
    assert build.returncode != 0
    try:
        check_built(build)
    except AssertionError as error:
        message = str(error)
    else:
        raise AssertionError("a failing example passed")
    assert "plot_wrong_number.py" in message and "0.75 is not 1" in message
