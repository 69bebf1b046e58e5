"""The case loader under random input (hypothesis): every input loads or gives a one-line CaseError.

Inputs: random nested values as a whole case (types, NaN/inf, huge numbers, unicode, deep nesting,
keys that are not strings, objects no TOML file holds); a valid case with one value replaced or one
key added; ``--set`` overrides (random keys and TOML-ish text) and dict overrides; random TOML
text and bytes in a case file; sources and overrides of the wrong type. Any other exception, or a
message on several lines, fails. ``VPCONTACT_FUZZ_EXAMPLES`` sets the examples per test (200).
"""

import copy
import math
import os

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import vpcontact
from vpcontact.case.load import MAX_NESTING
from vpcontact.errors import LONGEST_MESSAGE
from vpcontact.errors import CaseError
from conftest import half_disc_case, rectangle_case

#: 200 fixed examples in the test suite (the same on every machine: CI never fails by chance);
#: VPCONTACT_FUZZ_EXAMPLES=N draws N new random ones (a fuzzing session).
FUZZING = "VPCONTACT_FUZZ_EXAMPLES" in os.environ
SETTINGS = settings(max_examples=int(os.environ.get("VPCONTACT_FUZZ_EXAMPLES", 200)), deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
                    database=None, derandomize=not FUZZING)

KEYS = ["mesh", "shape", "h", "file", "radius", "width", "height", "material", "E", "nu", "hypothesis",
        "viscoplastic", "law", "eta", "yield_stress", "mu", "E_inf", "nu_inf", "initial", "stress", "boundary",
        "dirichlet", "part", "components", "traction", "value", "body_force", "contact", "g", "gap", "p",
        "exponent", "rho", "probe", "stiffness", "c_v", "alpha", "beta", "time", "T", "steps", "solver", "method",
        "factorization", "tolerance", "max_iterations", "max_step_cuts", "augmentation", "output", "field_steps",
        "progress", "checkpoint_every_steps", "checkpoint_every_seconds", "figures", "base_dir"]


class Opaque:
    """An object of the API no case file holds, whose repr fails."""

    def __repr__(self):
        raise RuntimeError("no repr")


numbers = st.one_of(
    st.integers(), st.integers(min_value=-(2 ** 80), max_value=2 ** 80).map(lambda i: i * 10 ** 300),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -0.0, 1e308, -1e308, 5e-324, 2 ** 63, 2 ** 64]),
    st.integers(min_value=4000, max_value=6000).map(lambda digits: -(10 ** digits)),  # beyond str(int)'s limit
)
texts = st.one_of(st.text(max_size=30), st.sampled_from(
    ["inf", "nan", "-inf", "auto", "all", "final", "1e999", "x*y*t", "t**1000", "((((((((x))))))))", "\n", "\x00",
     "\u2028", "half_disc", "rectangle", "power", "constant", "perzyna", "é∂ƒ", "9" * 400, "(" * 500, "1/0",
     "__import__('os')", "bottom_arc", "top_arc"]))
scalars = st.one_of(st.none(), st.booleans(), numbers, texts,
                    st.sampled_from([b"bytes", frozenset({1, 2}), (1, 2), 1j]), st.builds(Opaque), st.builds(object))
keys = st.one_of(st.sampled_from(KEYS), st.text(max_size=12))
odd_keys = st.one_of(keys, st.integers(), st.none(), st.tuples(st.text(max_size=3)))
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                       st.dictionaries(odd_keys, inner, max_size=5)), max_leaves=25)


def check(load):
    """Call ``load``: a Case, or a CaseError with a one-line message; anything else fails."""
    try:
        case = load()
    except CaseError as error:
        message = str(error)
        assert message and len(message.splitlines()) == 1 and message.isprintable(), repr(message)
        assert len(message) <= LONGEST_MESSAGE, message
        return None
    assert isinstance(case, vpcontact.Case)
    return case


def _paths(data, prefix=()):
    """Every path to a value in nested dicts and lists."""
    yield prefix
    if isinstance(data, dict):
        for key, value in data.items():
            yield from _paths(value, (*prefix, key))
    elif isinstance(data, list):
        for i, value in enumerate(data):
            yield from _paths(value, (*prefix, i))


def _replace(data, path, value):
    if not path:
        return value
    node = data
    for step in path[:-1]:
        node = node[step]
    node[path[-1]] = value
    return data


BASES = [half_disc_case(), rectangle_case()]
BASES[0]["material"]["viscoplastic"] = {"law": "perzyna", "eta": 0.5, "yield_stress": 3.0}
BASES[1]["material"]["viscoplastic"] = {"law": "relaxation", "mu": 1.0, "E_inf": 500.0, "nu_inf": 0.2}
BASES[1]["initial"] = {"stress": [[1.0, 0.5], [0.5, -2.0]]}
PATHS = [(b, p) for b in range(len(BASES)) for p in _paths(BASES[b])]


@SETTINGS
@given(values)
def test_any_value_as_a_whole_case(data):
    check(lambda: vpcontact.load_case(data))


@SETTINGS
@given(st.sampled_from(PATHS), values)
def test_one_value_of_a_valid_case_replaced(where, value):
    base, path = where
    data = _replace(copy.deepcopy(BASES[base]), path, value)
    case = check(lambda: vpcontact.load_case(data))
    if case is not None:  # what loads is finite where it must be
        assert math.isfinite(case.time.T) and 1 <= case.time.steps and case.material.E > 0
        assert math.isfinite(case.solver.tolerance) and case.solver.max_step_cuts >= 0


@SETTINGS
@given(st.sampled_from(PATHS), odd_keys, values)
def test_one_key_of_a_valid_case_added(where, key, value):
    base, path = where
    data = copy.deepcopy(BASES[base])
    node = data
    for step in path:
        node = node[step]
    if isinstance(node, dict):
        node[key] = value
    check(lambda: vpcontact.load_case(data))


override_keys = st.one_of(
    st.sampled_from([".".join(str(s) if isinstance(s, str) else f"[{s}]" for s in p).replace(".[", "[")
                     for _, p in PATHS if p]),
    st.text(max_size=25), st.sampled_from(["a..b", ".", "[0]", "boundary.traction[99].value", "mesh.h[0]",
                                           "boundary.traction[0].value[5]", "x" * 300, "time[0]", "time.T.x",
                                           "base_dir", "mesh.h[99999999999999999999999]"]),
)
override_texts = st.one_of(texts, st.sampled_from(
    ["[1, 2]", "{a = 1}", "1e400", "-1e400", "nan", "true", '"inf"', "[[1, 2], [2, 1]]", "0x10", "1979-05-27",
     "'''a'''", "[" * 3000, "1" + "0" * 5000, '"a\\nb"', "{" * 100]))


@SETTINGS
@given(st.sampled_from(range(len(BASES))), st.lists(st.tuples(override_keys, override_texts), max_size=4))
def test_set_overrides(base, pairs):
    overrides = [f"{key}={text}" for key, text in pairs]
    check(lambda: vpcontact.load_case(copy.deepcopy(BASES[base]), overrides))


@SETTINGS
@given(st.sampled_from(range(len(BASES))), st.dictionaries(st.one_of(override_keys, odd_keys), values, max_size=4))
def test_dict_overrides(base, overrides):
    check(lambda: vpcontact.load_case(copy.deepcopy(BASES[base]), overrides))


@SETTINGS
@given(st.one_of(st.text(max_size=200), st.binary(max_size=200).map(bytes.hex),
                 st.sampled_from(["a = " + "[" * 2000 + "]" * 2000, "a = 1" + "0" * 5000, "[mesh]\nh = nan",
                                  "[time]\nT = inf\nsteps = 1", "x = 1979-05-27T07:32:00Z"])),
       st.binary(max_size=64))
def test_case_files(tmp_path_factory, text, raw):
    folder = tmp_path_factory.mktemp("files")
    (folder / "text.toml").write_text(text, encoding="utf-8")
    (folder / "raw.toml").write_bytes(raw)
    for name in ("text.toml", "raw.toml", "missing.toml", ".", "bad\x00name.toml"):
        check(lambda: vpcontact.load_case(folder / name if "\x00" not in name else str(folder) + "/" + name))


@pytest.mark.parametrize("source", [None, 3, 2.5, ["a"], b"case.toml", ("mesh",), Opaque()])
def test_sources_and_overrides_of_other_types(source):
    check(lambda: vpcontact.load_case(source))
    for overrides in (5, "mesh.h=1", [1], [b"mesh.h=1"], {1: 2}, {"mesh.h": Opaque()}, {"mesh.h": {1, 2}}):
        check(lambda: vpcontact.load_case(copy.deepcopy(BASES[0]), overrides))


def test_what_the_fuzzer_found():
    """The inputs that gave tracebacks or unreadable messages before the loader was hardened."""
    def nested(depth, make):
        data = value = make()
        for _ in range(depth):
            value = _inner(value, make)
        return data

    def _inner(value, make):
        child = make()
        if isinstance(value, dict):
            value["a"] = child
        else:
            value.append(child)
        return child

    deep = [(nested(3000, dict), f"nested more than {MAX_NESTING} levels"),
            ({**BASES[0], "mesh": {"shape": "half_disc", "h": nested(3000, list)}}, "nested more than"),
            ({**BASES[0], 1: 2}, "keys must be strings"),
            ({**BASES[0], "mesh": {"shape": "half_disc", "h": Opaque()}}, "mesh.h = a value of type Opaque"),
            ({**BASES[0], "time": {"T": 1.0, "steps": 10 ** 5000}}, "time.steps = an integer of about 5001 digits"),
            ({**BASES[0], "time": {"T": 1.0, "steps": 10 ** 30}}, "must be <= 100000000"),
            ({**BASES[0], "mesh": {"shape": "half_disc", "h": 5e-324}}, "triangles"),
            ({**BASES[0], "mesh": {"shape": "half\ndisc", "h": 0.1}}, 'mesh.shape = "half\\ndisc"'),
            ({**BASES[0], "me\u2028sh": 1}, "unknown key 'me\\u2028sh'"),
            ({**BASES[0], "output": [[-(10 ** 310)] * 40] * 3}, "output = [[")]
    for data, expected in deep:
        with pytest.raises(CaseError) as error:
            vpcontact.load_case(data)
        message = str(error.value)
        assert expected in message and len(message.splitlines()) == 1 and len(message) < 200, message
    for overrides, expected in ((["mesh.h=" + "[" * 3000], "mesh.h = \"[[["), (["mesh.h=1" + "0" * 5000], "mesh.h"),
                                ([1], "--set 1"), (5, "not int"), ({1: 2}, "override key 1")):
        with pytest.raises(CaseError, match=None) as error:
            vpcontact.load_case(copy.deepcopy(BASES[0]), overrides)
        assert expected in str(error.value), str(error.value)
    for source in (None, b"x.toml", "bad\x00name.toml"):
        with pytest.raises(CaseError):
            vpcontact.load_case(source)
