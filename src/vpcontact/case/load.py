"""Loading a case: a TOML file or a dict, ``--set key=value`` overrides applied to the raw data, checked as a
TOML file holds it, validated, and every expression parsed once; the tables of the Python API validated alike."""

from __future__ import annotations

import datetime
import os
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from ..errors import CaseError, brief, one_line
from ..expressions.parse import parse_expression
from ..inputs import MAX_TOML_BYTES, check_regular_file
from .messages import describe, dotted
from .model import Case, Model
from .values import Section


def load_case(source: str | Path | dict, overrides: dict | list[str] | None = None) -> Case:
    """Read and validate a case from a TOML file or a dict, after applying dotted-key overrides.

    ``overrides``: {"contact.stiffness.beta": -1} or ["contact.stiffness.beta=-1", ...] (values are
    TOML: ``-1``, ``"inf"``, ``[1, 2]``; a value that is not TOML is taken as a string).
    Whatever the input, the result is a Case or a CaseError with a one-line message.
    """
    try:
        return _load_case(source, overrides)
    except CaseError as error:
        raise CaseError(one_line(str(error))) from None


def read_case(folder: str | os.PathLike) -> Case:
    """case.resolved.toml of the run in ``folder`` (CaseError when it is missing or not a case)."""
    return load_case(Path(folder) / "case.resolved.toml")


def _load_case(source, overrides) -> Case:
    base_dir = "."
    if isinstance(source, dict):
        data = plain(source)
        check_tree(data)
    elif isinstance(source, (str, os.PathLike)):
        try:
            path = Path(source)
        except TypeError:
            raise CaseError(f"case file {brief(source)}: not a file name") from None
        check_regular_file(path, "case file", MAX_TOML_BYTES)
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise CaseError(f"case file '{path}' not found") from None
        except (OSError, UnicodeDecodeError, ValueError) as error:  # ValueError: a NUL in the name
            raise CaseError(f"case file '{path}' cannot be read: {error}") from None
        try:
            data = tomllib.loads(text)
        except ValueError as error:  # TOMLDecodeError, or an integer of more than 4300 digits
            raise CaseError(f"case file '{path}' is not valid TOML: {error}") from None
        except RecursionError:
            raise CaseError(f"case file '{path}' is not valid TOML: nested too deeply") from None
        check_tree(data)
        base_dir = str(path.parent)
    else:
        raise CaseError(f"a case is a TOML file name or a table (dict), not {type(source).__name__}")
    for key, value in _parse_overrides(overrides).items():
        check_tree(value, (key,))
        _set_dotted(data, key, value)
    if "base_dir" in data:
        raise CaseError("unknown key 'base_dir'")
    try:
        case = Case.model_validate({**data, "base_dir": base_dir})
    except ValidationError as error:
        raise CaseError(describe(error.errors()[0])) from None
    check_expressions(case)
    return case


#: Deepest nesting of tables and lists accepted in a case (a case needs 5).
MAX_NESTING = 32
_VALUE_TYPES = (str, bool, int, float, list, dict, datetime.date, datetime.time)  # what TOML holds


def check_tree(data, prefix: tuple = ()) -> None:
    """Refuse what no TOML file holds before it reaches the validation: tables nested deeper than
    MAX_NESTING, keys that are not strings, values of other types (sets, bytes, objects).
    ``prefix``: where ``data`` sits in the case (an override's key)."""
    stack = [(data, prefix, 0)]
    while stack:
        value, path, depth = stack.pop()
        if depth > MAX_NESTING:
            raise CaseError(f"{dotted(path[:4])}...: nested more than {MAX_NESTING} levels deep")
        if not isinstance(value, _VALUE_TYPES):
            raise CaseError(f"{dotted(path) or 'the case'} = {_type_name(value)}: not a value a case file can hold "
                            f"(a number, string, boolean, list or table)")
        if isinstance(value, int) and value.bit_length() > 13000:  # Python cannot even print it (4300 digits)
            raise CaseError(f"{dotted(path) or 'the case'} = {brief(value)}: too large for any value of a case")
        if isinstance(value, dict):
            for key, item in value.items():
                if not isinstance(key, str):
                    raise CaseError(f"key {_type_name(key)} in {dotted(path) or 'the case'}: keys must be strings")
                stack.append((item, (*path, key), depth + 1))
        elif isinstance(value, list):
            stack.extend((item, (*path, i), depth + 1) for i, item in enumerate(value))


def _type_name(value) -> str:
    """A value for a message without calling its repr (any object may be given)."""
    if isinstance(value, (int, float, str, bytes, type(None))):
        return brief(value)
    return f"a value of type {type(value).__name__}"


#: The Python value a NumPy number of each kind is in a case (a complex number, a date: none, refused by key).
_PLAIN = {"b": bool, "i": int, "u": int, "f": float, "U": str}


def plain(value, depth: int = 0):
    """A copy of ``value`` (a case's table, list or value given from Python) holding the plain values a case
    file holds instead of NumPy's, through its tables (any mapping, made a dict) and lists: a NumPy number
    (``np.float32(1000)``, ``np.int64(10)``) and a 0-d array of one become the Python float or int,
    ``np.bool_`` a bool, ``np.str_`` a str, an array of one or more dimensions and a tuple the (nested) list
    of their values (``np.array([0, -1])`` -> ``[0, -1]``). Anything else is left as it is, for the
    validation to accept or refuse by its key (a complex number, an object): NaN and inf stay NaN and inf,
    refused where a finite number is wanted, and a NumPy bool is a bool, refused where a number is wanted.
    Below MAX_NESTING levels nothing is changed (:func:`_check_tree` refuses such nesting)."""
    if depth > MAX_NESTING:
        return value
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, np.generic):
        convert = _PLAIN.get(value.dtype.kind)
        return value if convert is None else convert(value)
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, Mapping):
        return {key: plain(item, depth + 1) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(item, depth + 1) for item in value]
    return value


def section(model: type[Section], value, key: str):
    """The table ``value`` of the section [``key``] given from Python (an argument of the API) as its
    ``model`` (:class:`OutputSection`, :class:`AdaptSection`, ...): None its defaults, an instance of it as it
    is, a dict validated as the case file's table (NumPy values as numbers, see :func:`plain`); anything
    else, or a bad value in it, is a CaseError naming the key (``output.field_steps = ...``)."""
    if isinstance(value, model):
        return value
    if value is not None and not isinstance(value, Mapping):
        raise CaseError(f"{key} = {brief(value)}: expected a table (dict) of the [{key}] keys (or a "
                        f"{model.__module__}.{model.__name__})")
    data = plain(dict(value or {}))
    check_tree(data, (key,))
    try:
        return model.model_validate(data)
    except ValidationError as error:
        first = error.errors()[0]
        raise CaseError(describe({**first, "loc": (key, *first["loc"])})) from None


def _parse_overrides(overrides) -> dict:
    if overrides is None:
        return {}
    if isinstance(overrides, dict):
        for key in overrides:
            if not isinstance(key, str):
                raise CaseError(f"override key {_type_name(key)}: expected a dotted key such as contact.stiffness.beta")
        return {key: plain(value) for key, value in overrides.items()}
    if not isinstance(overrides, (list, tuple)):
        raise CaseError(f"overrides: expected a dict or a list of \"key=value\" strings, not {type(overrides).__name__}")
    parsed = {}
    for item in overrides:
        if not isinstance(item, str):
            raise CaseError(f"--set {_type_name(item)}: expected a \"key=value\" string")
        key, sep, text = item.partition("=")
        if not sep or not key.strip():
            raise CaseError(f"--set {brief(item)}: expected key=value, e.g. contact.stiffness.beta=-1")
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except (ValueError, RecursionError):  # not TOML (or an integer of more than 4300 digits)
            value = text
        parsed[key.strip()] = value
    return parsed


_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")


def _set_dotted(data: dict, dotted: str, value) -> None:
    """Set data[a][b][i][c] = value for the key "a.b[i].c", creating tables as needed."""
    steps: list[str | int] = []
    for piece in dotted.split("."):
        match = _KEY.match(piece)
        if match is None:
            raise CaseError(f"override key {brief(dotted)} is not a dotted key such as contact.stiffness.beta")
        steps.append(match.group(1))
        steps += [int(i) if len(i) <= 18 else 10**18 for i in re.findall(r"\[(\d+)\]", match.group(2))]
    node = data
    for position, step in enumerate(steps[:-1]):
        if isinstance(step, int):
            if not isinstance(node, list) or step >= len(node):
                raise CaseError(f"override key {brief(dotted)}: no entry [{step}] there")
            node = node[step]
        else:
            if not isinstance(node, dict):
                raise CaseError(f"override key {brief(dotted)}: '{step}' is not inside a table")
            if step not in node and isinstance(steps[position + 1], int):
                raise CaseError(f"override key {brief(dotted)}: no list '{step}' to index")
            node = node.setdefault(step, {})
    last = steps[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last >= len(node):
            raise CaseError(f"override key {brief(dotted)}: no entry [{last}] there")
    elif not isinstance(node, dict):
        raise CaseError(f"override key {brief(dotted)}: '{last}' is not inside a table")
    node[last] = value


def check_expressions(case: Model) -> None:
    """Parse every expression once, so that a bad one is reported with its key before any work."""
    for i, traction in enumerate(case.boundary.traction):
        for c, value in enumerate(traction.value):
            parse_expression(value, ("x", "y", "z", "t"), where=f"boundary.traction[{i}].value[{c}]")
    for i, force in enumerate(case.boundary.body_force):
        for c, value in enumerate(force.value):
            parse_expression(value, ("x", "y", "z", "t"), where=f"boundary.body_force[{i}].value[{c}]")
    if case.contact is not None:
        for key, layer in case.contact.layers():
            parse_expression(layer.gap, ("x", "y", "z"), where=f"{key}.gap")
    for key, material in case.keyed_materials():
        parse_expression(material.E, ("x", "y", "z"), where=f"{key}.E")
        parse_expression(material.nu, ("x", "y", "z"), where=f"{key}.nu")
    initial = case.initial
    for i, row in enumerate(initial.stress or ()):
        for j, value in enumerate(row):
            parse_expression(value, ("x", "y", "z"), where=f"initial.stress[{i}][{j}]")
    for i, value in enumerate(initial.displacement or ()):
        parse_expression(value, ("x", "y", "z"), where=f"initial.displacement[{i}]")
    if initial.xi is not None:
        parse_expression(initial.xi, ("x", "y", "z"), where="initial.xi")
