"""The reproduction of Sect. 4 of the paper: ``vpcontact reproduce --out DIR [--quick]``.

Nothing else in the package imports this subpackage: the command line imports it when the
``reproduce`` command runs. One module per idea, each importing only those above it:

- :mod:`.paper`        what the paper states: its example, its numbers, its four contact conditions;
- :mod:`.plan`         the sizes of a reproduction (full or ``--quick``) and the runs solved in this process;
- :mod:`.study_files`  the parameter studies it runs (Figs. 8–10, the rates in h and in k), as study files;
- :mod:`.calibration`  the load that gives the paper's K = 323 with the fine time step;
- :mod:`.runs`         solving a case or a study and what reproduce.json keeps of a run;
- :mod:`.records`      the studies' numbers: differences, slopes, effectivity, adaptive against uniform;
- :mod:`.claims`       every number or claim of Sect. 4, paper against vpcontact, with a verdict;
- :mod:`.frames`       the deformed configurations the figures draw, from results or run directories;
- :mod:`.figures`      Figs. 2–11 (matplotlib, PNG and PDF);
- :mod:`.markup`       the report's blocks, rendered to Markdown and to HTML, and how it writes a number;
- :mod:`.comparison`   its sections setting vpcontact beside the paper's values: claims, load, time step,
                       ordering of penetrations, deviations;
- :mod:`.figure_section`  its Figures section: Figs. 2–10, their captions and the tables of their numbers;
- :mod:`.beyond_paper` its section Beyond the paper: rates in h and in k, effectivity, adaptive meshes;
- :mod:`.report`       report.md and report.html: the opening, the sections in order, the machine;
- :mod:`.timing`, :mod:`.machine`  how long each part took, and where;
- :mod:`.reproduce`    the whole reproduction into DIR (`reproduce.run`).
"""
