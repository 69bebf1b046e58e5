"""``result.plot``: the figures of :mod:`vpcontact.results.plots` as methods of one run, each returning a
`matplotlib.figure.Figure` (no pyplot: a notebook shows it as it is, ``figure.savefig(...)`` writes it)."""

from __future__ import annotations

import numpy as np

from . import plots


class ResultPlots:
    """The figures of ``result``:

    - ``time_series(columns)``: history columns against t (:func:`vpcontact.results.plots.time_series`);
    - ``contact_pressure(step)``: the contact pressure and node states on Γ3, along Γ3 in 2D, over the
      contact patch in 3D, at a step or a list of steps (default: four spread over the run);
    - ``states(step)``: the node states and the penetration on Γ3 at one step (default: the last);
    - ``deformed(step, field, scale)``: the deformed body coloured by a field
      (:func:`vpcontact.results.plots.body_fields` names them: ``von_mises``, ``displacement``, ``sigma_xx``, …,
      ``error_indicator``);
    - ``force_displacement(part, force, displacement)``: a Dirichlet part's reaction against its mean displacement;
    - ``contact_area()``: the contact and limit areas against t.
    """

    def __init__(self, result):
        self.result = result

    def __repr__(self) -> str:
        return ("ResultPlots: time_series(columns), contact_pressure(step), states(step), deformed(step, field, scale), "
                "force_displacement(part, force, displacement), contact_area()")

    def time_series(self, columns=plots.TIME_SERIES):
        """History ``columns`` (see ``result.columns``) against t, one panel each."""
        return plots.time_series(self.result, columns)

    def contact_pressure(self, step=None):
        """The contact pressure and node states at ``step`` (a step number or a list of them; default: about
        four steps spread over the run, the last included), one panel per step."""
        steps = [step] if step is not None and np.ndim(step) == 0 else step
        return plots.contact_pressure(self.result, steps)

    def states(self, step=None):
        """The node states and the penetration on Γ3 at the end of ``step`` (default: the last step done)."""
        return plots.node_states(self.result, step)

    def deformed(self, step=None, field="von_mises", scale=None):
        """The body deformed at a field ``step`` (default: the last one kept), magnified ``scale`` times
        (default: its largest displacement drawn at a tenth of its size), coloured by ``field``."""
        return plots.deformed_body(self.result, step, scale, field)

    def force_displacement(self, part, force="y", displacement="y"):
        """The reaction of the Dirichlet ``part`` in the component ``force`` against its mean displacement in the
        component ``displacement`` (``reaction_<part>_<force>``, ``displacement_<part>_<displacement>``)."""
        return plots.force_displacement(self.result, part, force, displacement)

    def contact_area(self):
        """The contact area (Σ w_i where d_i > 0) and the limit area against t (``contact_area``, ``limit_area``)."""
        return plots.time_series(self.result, ("contact_area", "limit_area"))
