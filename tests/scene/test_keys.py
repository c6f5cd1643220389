"""The vocabulary of scene keys (:mod:`impactcont.scene.keys`): each value type returns what
it accepts and refuses the rest with a SceneError naming the key path, the value (as TOML)
and what is allowed; ``read_table`` refuses unknown keys with a hint and missing required
ones."""

from __future__ import annotations

import dataclasses
import math

import pytest

from impactcont.errors import ImpactcontError
from impactcont.scene import keys as k

HERE = k.Where("scene.toml", "branches[1]")


def _refused(value_type: k.ValueType, value, key: str = "x") -> str:
    with pytest.raises(k.SceneError) as info:
        value_type.check(value, HERE.key(key))
    return str(info.value)


def test_a_scene_error_says_file_line_key_problem_and_what_is_allowed() -> None:
    error = k.SceneError("out of range; got 0", key="branches[1].N", allowed="an integer >= 1",
                         file="s.toml", line=7)
    assert str(error) == "s.toml:7: branches[1].N: out of range; got 0; allowed: an integer >= 1"
    assert isinstance(error, ValueError) and isinstance(error, ImpactcontError)
    assert (error.key, error.allowed, error.line) == ("branches[1].N", "an integer >= 1", 7)
    assert str(k.SceneError("not TOML")) == "<scene>: not TOML"


def test_where_builds_the_key_path_and_finds_its_line() -> None:
    where = k.Where("s.toml", "", locate=lambda path: {"plots[0].kind": 12}.get(path))
    kind = where.key("plots").item(0).key("kind")
    assert kind.path == "plots[0].kind"
    assert str(kind.error("unknown", "one of a, b")) == ("s.toml:12: plots[0].kind: unknown; "
                                                        "allowed: one of a, b")
    assert kind.key("x").error("bad").line is None


@pytest.mark.parametrize(("value", "text"), [
    (True, "true"), ("a\"b", '"a\\"b"'), ([1, 2.5], "[1, 2.5]"),
    ({"b": [0.1, 0.2]}, "{b = [0.1, 0.2]}"), (None, "None"),
])
def test_show_writes_a_value_as_toml(value, text) -> None:
    assert k.show(value) == text


def test_type_names() -> None:
    assert [k.type_name(v) for v in (True, 1, 1.0, "s", [], {})] == [
        "a boolean", "an integer", "a float", "a string", "an array", "a table"]


def test_a_real_takes_integers_and_floats_inside_its_range() -> None:
    unit = k.Real(0.0, 1.0, low_open=True)
    assert unit.allowed == "a real number in (0, 1]"
    assert unit.check(1, HERE) == 1.0 and isinstance(unit.check(1, HERE), float)
    assert _refused(unit, 0) == ("scene.toml: branches[1].x: out of range; got 0 (an "
                                 "integer); allowed: a real number in (0, 1]")
    assert "wrong type; got true (a boolean)" in _refused(unit, True)
    assert "wrong type; got \"0.5\" (a string)" in _refused(unit, "0.5")
    assert "out of range; got nan" in _refused(k.Real(), math.nan)
    assert k.Real(2.0).allowed == "a real number >= 2"
    assert k.Real(high=3.0, high_open=True).allowed == "a real number < 3"


def test_an_integer_in_a_range_or_of_a_few_values() -> None:
    assert k.Integer(1, 1000).check(7, HERE) == 7
    assert "got 1.0 (a float); allowed: an integer in [1, 1000]" in _refused(
        k.Integer(1, 1000), 1.0)
    assert "out of range; got 0 (an integer); allowed: one of +1, -1" in _refused(
        k.Integer(choices=(1, -1)), 0)
    assert "allowed: an integer >= 2" in _refused(k.Integer(2), 1)


def test_booleans_strings_and_parameter_names_suggest_the_close_value() -> None:
    assert k.Boolean().check(False, HERE) is False
    assert "wrong type; got 1 (an integer); allowed: true or false" in _refused(k.Boolean(), 1)
    which = k.String(("all", "physical", "stable"))
    assert which.check("stable", HERE) == "stable"
    assert ('did you mean "physical"?; got "physcal" (a string); allowed: one of "all", '
            '"physical", "stable"') in _refused(which, "physcal")
    assert "not a known value" in _refused(which, "zzz")
    name = k.ParameterName()
    assert name.check("M[1,2]", HERE) == "M[1,2]" and name.check("k2", HERE) == "k2"
    assert 'did you mean "omega"?; got "omga"' in _refused(name, "omga")
    assert 'did you mean "M[1,2]"?; got "M[1, 2]"' in _refused(name, "M[1, 2]")
    assert 'or an element name m<j>, k<j>' in name.allowed


def test_entry_names_are_identifiers() -> None:
    assert k.ENTRY_NAME.check("br_1", HERE) == "br_1"
    assert k.NAME_PATTERN.match("a1_b") and not k.NAME_PATTERN.match("1a")
    assert f"invalid; got \"1br\" (a string); allowed: {k.NAME_ALLOWED}" in _refused(
        k.ENTRY_NAME, "1br")
    names = k.Names()
    assert names.check("br", HERE) == ("br",)  # one name alone
    assert names.check(["a", "b"], HERE) == ("a", "b")
    assert "wrong type or empty; got []" in _refused(names, [])
    assert "repeated name; got [\"a\", \"a\"]" in _refused(names, ["a", "a"])
    assert "branches[1].x[1]: invalid; got \"b-c\"" in _refused(names, ["a", "b-c"])


def test_a_string_list_has_distinct_known_values() -> None:
    labels = k.StringList(("SN", "PD", "NS"))
    assert labels.check(["PD", "SN"], HERE) == ("PD", "SN")
    assert labels.check([], HERE) == ()
    assert "repeated value; got [\"SN\", \"SN\"]" in _refused(labels, ["SN", "SN"])
    assert "branches[1].x[1]: not a known value; got \"XY\"" in _refused(labels, ["SN", "XY"])


def test_real_arrays_are_vectors_or_square_matrices() -> None:
    assert k.RealArray(1).check([1, 2.5], HERE) == (1.0, 2.5)
    assert k.RealArray(2).check([[1, 0], [0, 2]], HERE) == ((1.0, 0.0), (0.0, 2.0))
    assert "not a square array of rows; got [[1, 2], [3]]" in _refused(k.RealArray(2),
                                                                       [[1, 2], [3]])
    assert ("entry 0 is not allowed; got [1, 0] (an array); allowed: a non-empty array of "
            "real numbers, all > 0") in _refused(k.RealArray(1, positive=True), [1, 0])
    assert "all >= 0" in _refused(k.RealArray(1, nonnegative=True), [-1])
    assert "wrong type or empty; got []" in _refused(k.RealArray(1), [])


def test_an_interval_is_an_increasing_pair_inside_its_bound() -> None:
    positive = k.Interval(k.Real(0.0))
    assert positive.check([0, 2], HERE) == (0.0, 2.0)
    assert positive.allowed == "a pair [lo, hi] of real numbers with lo < hi, each >= 0"
    assert "lo must be < hi; got [2, 1]" in _refused(positive, [2, 1])
    assert "out of range; got [-1, 1]" in _refused(positive, [-1, 1])
    assert "not a pair; got [1]" in _refused(positive, [1])
    assert "wrong type; got [1, true]" in _refused(positive, [1, True])
    assert k.Interval().allowed == "a pair [lo, hi] of real numbers with lo < hi"


@dataclasses.dataclass(frozen=True, kw_only=True)
class _Table:
    name: str = k.declare(k.ENTRY_NAME, "entry name", "")
    N: int = k.declare(k.Integer(1), "periods", 1)
    bounds: tuple = k.declare(k.Interval(), "range", required=True)
    plain: int = 0  # not a scene key


def test_declared_fields_are_the_keys_of_a_table() -> None:
    keys = k.scene_keys(_Table)
    assert list(keys) == ["name", "N", "bounds"]
    assert keys["bounds"].required and not keys["N"].required
    assert keys["N"].doc == "periods" and keys["N"].type.allowed == "an integer >= 1"


def test_read_table_checks_every_key_and_refuses_unknown_and_missing_ones() -> None:
    assert k.read_table(_Table, {"bounds": [1, 2], "N": 3}, HERE) == {"N": 3,
                                                                     "bounds": (1.0, 2.0)}
    with pytest.raises(k.SceneError, match=r"^scene.toml: branches\[1\].bound: unknown key; did "
                                           r"you mean 'bounds'\?; allowed: name, N, bounds$"):
        k.read_table(_Table, {"bound": [1, 2]}, HERE)
    with pytest.raises(k.SceneError, match=r"branches\[1\].n: unknown key; did you mean 'N'\?"):
        k.read_table(_Table, {"n": 2, "bounds": [1, 2]}, HERE)
    with pytest.raises(k.SceneError, match=r"branches\[1\].plain: unknown key; not a key of this "
                                           r"table"):
        k.read_table(_Table, {"plain": 1}, HERE)
    with pytest.raises(k.SceneError, match=r"branches\[1\].bounds: required key is missing; "
                                           r"allowed: a pair \[lo, hi\]"):
        k.read_table(_Table, {"N": 2}, HERE)
    with pytest.raises(k.SceneError, match=r"branches\[1\]: must be a table; got 3 \(an "
                                           r"integer\); allowed: keys name, N, bounds"):
        k.read_table(_Table, 3, HERE)
    assert k.read_table(_Table, {"bounds": [1, 2], "kind": "x"}, HERE, extra=("kind",)) == {
        "bounds": (1.0, 2.0)}


def test_the_dpi_range() -> None:
    assert k.DPI_RANGE == (10, 1200)
