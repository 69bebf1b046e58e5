"""``[material]``: isotropic elasticity, optionally a viscoplastic law (its table:
:mod:`vpcontact.case.law_sections`), for the whole body or by region."""

from __future__ import annotations

from typing import Annotated, Any, Literal, Optional, Union

from pydantic import AfterValidator, Discriminator, Field, Tag

from ..errors import brief
from .law_sections import Viscoplastic, poisson_ratios
from .values import Expression, Section, finite


def _check_poisson_ratio(key: str, nu: float, hypothesis: str | None) -> None:
    upper_ok = nu <= 0.5 if hypothesis == "plane_stress" else nu < 0.5
    if not (-1.0 < nu and upper_ok):
        bound = "<= 0.5" if hypothesis == "plane_stress" else "< 0.5"
        name = key.rpartition(".")[2]
        model = hypothesis or "plane_strain and 3D"
        raise ValueError(f"{key} = {brief(nu)}: must satisfy -1 < {name} {bound} for {model}")


def _modulus(value):
    """material.E: a number > 0 or an expression in the coordinates (checked > 0 at the element centroids)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not finite(value) or not value > 0:
        raise ValueError(f"= {brief(value)}: expected a finite number > 0 or an expression in the coordinates")
    return value


Modulus = Annotated[Any, AfterValidator(_modulus)]


def _region_names(value):
    """material.region: a region name (a string, or a physical group's number) or a non-empty list of them."""
    names = value if isinstance(value, list) else [value]
    if not names or any(isinstance(name, bool) or not isinstance(name, (str, int)) for name in names):
        raise ValueError(f"expected a region name (a string or a physical group number) or a non-empty list of them, "
                         f"got {brief(value)}")
    return value


class MaterialSection(Section):
    """Isotropic elasticity (4.1); in 2D plane strain (the paper's formula, the default) or plane
    stress, in 3D the full tensor (no hypothesis); optionally a viscoplastic law 𝒢 of (2.1) (none:
    𝒢 = 0, linear elasticity). E and ν are numbers or expressions in the coordinates (ℰ(x) of (2.16),
    evaluated at the element centroids). ``region``: the mesh regions (``Mesh.regions``) the entry is
    the material of; None: the whole body (then it is the only entry)."""

    E: Modulus
    nu: Expression
    hypothesis: Optional[Literal["plane_strain", "plane_stress"]] = None  # 2D only; None: plane strain in 2D
    viscoplastic: Optional[Viscoplastic] = None
    region: Optional[Annotated[Any, AfterValidator(_region_names)]] = None

    def check_poisson_ratios(self, key: str) -> None:
        """ValueError unless ν (a number) and the Poisson ratios of the viscoplastic law (relaxation's ν_inf) are
        admissible for the hypothesis; ``key`` names the entry in the message ("material" or "material[i]")."""
        if not isinstance(self.nu, str):
            _check_poisson_ratio(f"{key}.nu", self.nu, self.hypothesis)
        if self.viscoplastic is not None:
            for name, value in poisson_ratios(self.viscoplastic):
                _check_poisson_ratio(f"{key}.viscoplastic.{name}", value, self.hypothesis)

    @property
    def regions(self) -> list[str]:
        """The names of the regions of the entry (empty: the whole body)."""
        if self.region is None:
            return []
        return [str(name) for name in (self.region if isinstance(self.region, list) else [self.region])]


def _material_kind(value) -> str:
    return "list" if isinstance(value, list) else "table"


#: ``[material]`` (one material, the whole body) or ``[[material]]`` (a list of entries by region).
Materials = Annotated[Union[Annotated[MaterialSection, Tag("table")],
                            Annotated[list[MaterialSection], Field(min_length=1), Tag("list")]],
                      Discriminator(_material_kind)]
