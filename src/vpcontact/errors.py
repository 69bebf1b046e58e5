"""The one exception a user sees for bad input, and how its messages show a user's values."""

import json
import math


class CaseError(ValueError):
    """Bad input in a case (file, override or API call): a one-line message naming the bad value.

    The message is made one line when the error is made (:func:`one_line`), whatever it quotes (a
    value whose repr spans lines, a name with a newline): the command line prints it alone (no
    traceback) and exits with status 2, and the API shows the same line.
    """

    def __init__(self, *args):
        if args and isinstance(args[0], str):
            args = (one_line(args[0]), *args[1:])
        super().__init__(*args)


#: Most characters of a user's value a message shows; a longer value is cut and its length given, so
#: that the message stays one short line and its reason is never cut off.
SHOWN = 60


def shown(text: str) -> str:
    """``text`` as a message shows it: whole up to SHOWN characters, else its first SHOWN characters,
    "…" and the length of the whole, e.g. ``1+1+1+…+1 (1048575 characters)``."""
    if len(text) <= SHOWN:
        return text
    return f"{text[:SHOWN]}… ({len(text)} characters)"


def brief(value) -> str:
    """``repr(value)`` on one line, cut as :func:`shown` cuts: a huge integer by its number of digits, a value whose
    repr spans lines on one, any object of the API (whatever its repr does) at least by its type."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 200:
        sign = "a negative" if value < 0 else "an"
        return f"{sign} integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    try:
        text = repr(value)
    except Exception:  # noqa: BLE001 - an object of the API may have any repr
        return f"a value of type {type(value).__name__}"
    if "\n" in text:  # an object shown over several lines (a scikit-fem mesh, a table): one line
        text = " ".join(text.split())
    return shown(text)


def quoted(text: str) -> str:
    """A string value as a message shows it: in double quotes with control characters escaped as in
    TOML (JSON rules), cut as :func:`shown` cuts, e.g. ``"1+1+1+…" (1048575 characters)``."""
    escaped = json.dumps(text, ensure_ascii=False)[1:-1]
    if len(escaped) <= SHOWN:
        return f'"{escaped}"'
    return f'"{escaped[:SHOWN]}…" ({len(text)} characters)'


def flag(name: str, value) -> bool:
    """``value`` of the API's switch ``name`` (overwrite, progress, ...) as a bool: True or False (a NumPy bool
    too), else CaseError: a string such as "no" is not read as true."""
    if type(value).__name__ in ("bool", "bool_") and type(value).__module__ in ("builtins", "numpy"):
        return bool(value)
    raise CaseError(f"{name} = {shown(repr(value))}: expected True or False")


#: Longest message of a refusal (the command line cuts longer ones): a user's values are shown
#: shortened (:func:`shown`), so this cuts only the explanations of the longest mesh diagnoses.
LONGEST_MESSAGE = 800


def one_line(message: str) -> str:
    """The message on one line: control and separator characters escaped, at most LONGEST_MESSAGE long."""
    text = "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in message)
    return text if len(text) <= LONGEST_MESSAGE else text[: LONGEST_MESSAGE - 3] + "..."
