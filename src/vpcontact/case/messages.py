"""A pydantic validation error as the one line a user reads: the key as a case file writes it
(``contact.stiffness.beta``, ``material[0].E``), the value and what is expected; an unknown key with the
nearest valid one."""

from __future__ import annotations

import difflib
import typing

from pydantic import BaseModel

from ..errors import shown
from .law_sections import LAW_TAGS
from .model import Case
from .values import show


_TYPE_WORDS = {
    "float_type": "expected a number",
    "int_type": "expected an integer",
    "string_type": "expected a string",
    "bool_type": "expected true or false",
    "list_type": "expected a list",
    "model_type": "expected a table",
    "dict_type": "expected a table",
    "model_attributes_type": "expected a table",
    "finite_number": "expected a finite number",
}
_FORM_TAGS = {"material": ("table", "list")}  # a section given as one table or a list of them


def dotted(loc) -> str:
    text = ""
    for item in loc:
        text += f"[{item}]" if isinstance(item, int) else (f".{item}" if text else str(item))
    return text


def _clean_loc(loc) -> tuple:
    """Drop the discriminator tags pydantic inserts (contact.stiffness.power.beta -> contact.stiffness.beta,
    material.list.0.E -> material[0].E)."""
    cleaned = []
    for item in loc:
        tags = (*LAW_TAGS.get(cleaned[-1], ()), *_FORM_TAGS.get(cleaned[-1], ())) if cleaned else ()
        if item in tags or (cleaned and cleaned[-1] in ("part", "region") and item in ("str", "int")):
            continue  # a law's or a form's tag, or the member of the union str | int of a part or region name
        cleaned.append(item)
    return tuple(cleaned)


def describe(error: dict) -> str:
    loc = _clean_loc(error["loc"])
    key, kind, value = dotted(loc), error["type"], error.get("input")
    ctx = error.get("ctx", {})
    if kind == "extra_forbidden":
        return _unknown_key(loc, _law_tag(error["loc"]))
    if kind == "missing":
        return f"missing required value '{key}'"
    if kind == "value_error":
        message = str(ctx.get("error", error["msg"]))
        if message.startswith("= "):  # "= <value>: ..." of a validator that does not know its key
            return f"{key} {message}"
        if message.startswith("."):  # ".xi = <value>: ..." of a table's validator naming one of its keys
            return f"{key}{message}"
        if key in ("", "mesh", "material", "contact", "output") or message.startswith(key):
            return message
        name = loc[-1] if loc else ""
        if isinstance(name, str) and message.startswith(f"{name} "):  # "g = 0: ..." of the key contact.parts[1].g
            return key + message[len(name):]
        return f"{key}: {message}"
    if kind in ("union_tag_invalid", "union_tag_not_found"):
        laws = ", ".join(f'"{t}"' for t in LAW_TAGS.get(loc[-1] if loc else "", LAW_TAGS["stiffness"]))
        given = ctx.get("tag")
        if kind == "union_tag_not_found":
            return f"missing required value '{key}.law' (one of {laws})"
        return f"{key}.law = \"{given}\": unknown law; expected one of {laws}"
    if kind == "literal_error":
        return f"{key} = {show(value)}: expected one of {ctx.get('expected')}"
    limits = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}
    if kind in limits:
        bound = next(iter(ctx.values()))
        return f"{key} = {show(value)}: must be {limits[kind]} {bound}"
    if kind in ("too_short", "too_long"):
        bound = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        return (f"{key} = {show(value)}: expected {'at least' if kind == 'too_short' else 'at most'} {bound} "
                f"value{'s' * (bound != 1)}")
    return f"{key} = {show(value)}: {_TYPE_WORDS.get(kind, error['msg'])}"

def _law_tag(raw_loc) -> str | None:
    """The law a tagged union was validated as (the last tag pydantic inserts after "stiffness" etc.)."""
    tags = [item for before, item in zip(raw_loc, raw_loc[1:]) if item in LAW_TAGS.get(before, ())]
    return tags[-1] if tags else None


def _unknown_key(loc, law: str | None = None) -> str:
    valid = _valid_keys(loc[:-1], law)
    name = str(loc[-1])
    close = difflib.get_close_matches(name, valid, n=1)
    hint = f"did you mean '{dotted((*loc[:-1], close[0]))}'?" if close else f"valid keys: {', '.join(valid)}"
    return f"unknown key '{shown(dotted(loc))}' ({hint})"


def _valid_keys(loc, law: str | None = None) -> list[str]:
    """The keys allowed at ``loc`` (a path of section names and list indices); ``law`` picks the
    member of a tagged union of laws."""
    models = [Case]
    for item in loc:
        if isinstance(item, int):
            continue
        models = [inner for model in models if item in model.model_fields
                  for inner in _models_in(model.model_fields[item].annotation)]
    if law is not None and len(models) > 1:
        models = [model for model in models if law in typing.get_args(model.model_fields.get("law").annotation)] or models
    models = list(dict.fromkeys(models))  # a section given as a table or a list of them: one model
    keys = {k for model in models for k, f in model.model_fields.items() if not f.exclude}
    return sorted(keys)


def _models_in(annotation) -> list[type[BaseModel]]:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [model for arg in typing.get_args(annotation) for model in _models_in(arg)]
