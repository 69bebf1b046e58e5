"""The time grid of a run: t_n = t_0 + n k, n = 1, …, steps (k = (T − t_0) / steps), computed when asked for."""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence

import numpy as np

from ..errors import brief


class TimeGrid(Sequence):
    """The step times t_n = t_0 + n k, n = 1, …, steps, with t_steps = T exactly (bitwise the values of
    ``np.linspace(t_0, T, steps + 1)[1:]``), computed when asked for: a grid of 10⁸ steps costs nothing.
    t_0 = ``start`` (default 0: t_n = n k).

    Indexing gives t_n at index n − 1 (a NumPy float; negative indices count from the end), slicing and
    ``np.asarray`` give arrays, :meth:`at` gives t_n for an array of step numbers n.
    """

    def __init__(self, T: float, steps: int, start: float = 0.0):
        self.T, self.steps, self.start, self.k = T, steps, start, (T - start) / steps

    def at(self, n) -> np.ndarray:
        """t_n for step numbers n (an int or an array of ints in 1, …, steps)."""
        n = np.asarray(n)
        return np.where(n == self.steps, self.T, self.start + n * self.k)

    def __len__(self) -> int:
        return self.steps

    def __getitem__(self, index):
        if isinstance(index, slice):
            return self.at(np.arange(*index.indices(self.steps)) + 1).astype(float)
        position = operator.index(index)
        if not -self.steps <= position < self.steps:
            raise IndexError(f"time step index {position} out of range for {self.steps} steps")
        return np.float64(self.at(position % self.steps + 1))

    def __iter__(self):
        chunk = 2**16
        for start in range(0, self.steps, chunk):
            yield from self[start:start + chunk]

    def __array__(self, dtype=None, copy=None) -> np.ndarray:
        return self[:].astype(dtype or float)

    def __repr__(self) -> str:
        start = f", start={self.start!r}" if self.start else ""
        return f"TimeGrid(T={self.T!r}, steps={self.steps}{start})"


def check_time_span(start: float, T: float, steps: int, where: str) -> None:
    """ValueError unless t_0 = ``start`` (named ``where``) is before T by steps of a positive float64 length."""
    if not T > start:
        raise ValueError(f"time.T = {brief(T)} must be > {where} = {brief(start)}")
    if not (math.isfinite(T - start) and (T - start) / steps > 0):
        raise ValueError(f"{where} = {brief(start)}: the steps (T - {where}) / time.steps are not positive finite "
                         f"numbers in float64")
