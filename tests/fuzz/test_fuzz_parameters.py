"""Fuzz the one check of a parameter value and of a parameter file (issue 31, item 4).

Param.validate is what every node, the launcher and a sweep use; description.check is the
launcher's check of a run's values against every node that declares them; read_parameter_file
is how the nodes and the launcher read a file. Whatever they are given, they either accept it
(and then the value is one the node can use: finite, in range, an existing file of the right
format) or raise ParameterError with one line per problem; never another exception.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.tally import fuzz, tally

pytestmark = pytest.mark.ros  # the nodes' PARAMS import rclpy


def _all_params():
    from sgim_nodes.graph.description import NODES

    found = {}
    for spec in NODES.values():
        for param in spec.params:
            found[(spec.name, param.name)] = param
    return found


PARAMS = _all_params()
NAMES = sorted({name for _, name in PARAMS})
TEACHING_SET = str(Path(__import__("sim_bridge.data_files", fromlist=["x"]).data_dir())
                   / "teaching_set.npz")

# What YAML (a file, a --param, a sweep) can hand a parameter: every scalar type, lists,
# mappings, nothing, and the awkward corners of each (NaN, infinities, 2**63, NUL, paths).
paths = st.sampled_from(["", "/etc/passwd", "/", "/dev/null", "/nonexistent/x.npz", ".",
                         TEACHING_SET, "a\0b", "x" * 5000])
scalars = st.one_of(
    st.none(), st.booleans(),
    st.integers(), st.sampled_from([2**63 - 1, 2**63, -(2**63), -(2**63) - 1, 2**32 - 1,
                                    2**32, 10**20, 10**400]),
    st.floats(), st.sampled_from([math.inf, -math.inf, math.nan, 1e308, -0.0, 5e-324]),
    st.text(max_size=30), paths,
)
values = st.one_of(scalars, st.lists(scalars, max_size=4),
                   st.dictionaries(st.text(max_size=5), scalars, max_size=3))


def _one_line_each(error: Exception) -> None:
    lines = str(error).split("\n")
    assert all(line.strip() and len(line) < 2000 for line in lines), str(error)[:400]


def _accepted_is_usable(param, value) -> None:
    from sgim_ros.params import INT_MAX, Bounds, DataFile, OneOf

    expected = type(param.default)
    assert type(value) is expected, (param.name, value)
    if expected is float:
        assert math.isfinite(value), (param.name, value)
    if expected is int:
        assert -INT_MAX - 1 <= value <= INT_MAX
    if expected is str:
        assert "\0" not in value
    if isinstance(param.check, Bounds | OneOf):
        assert param.check(value), (param.name, value)
    if isinstance(param.check, DataFile) and value:
        assert Path(value).is_file() and Path(value).is_absolute()


@fuzz(600)
@given(key=st.sampled_from(sorted(PARAMS)), value=values)
def test_validate_accepts_a_usable_value_or_refuses_it_in_one_line(key, value):
    from sgim_ros.params import ParameterError

    param = PARAMS[key]
    try:
        checked = param.validate(value)
    except ParameterError as error:
        _one_line_each(error)
        assert "\n" not in str(error) and param.name in str(error)
        tally("Param.validate", "refused")
        return
    _accepted_is_usable(param, checked)
    tally("Param.validate", "accepted")


@fuzz(600)
@given(key=st.sampled_from(sorted(PARAMS)),
       value=st.one_of(st.just(None), st.integers(), st.floats(), st.text(max_size=10)))
def test_validate_keeps_a_good_value_of_the_right_type(key, value):
    """Around each parameter's own type: the edges of the ranges, the whole float line."""
    from sgim_ros.params import ParameterError

    param = PARAMS[key]
    if value is None:
        value = param.default
    try:
        checked = param.validate(value)
    except ParameterError as error:
        _one_line_each(error)
        tally("Param.validate (typed)", "refused")
        return
    _accepted_is_usable(param, checked)
    tally("Param.validate (typed)", "accepted")


def typed_values(name: str) -> st.SearchStrategy:
    """Values of a parameter's own kind, good ones often: its default, numbers around it,
    its choices, paths; and now and then anything at all."""
    from sgim_ros.params import OneOf

    param = next(p for (_, n), p in PARAMS.items() if n == name)
    default = param.default
    if isinstance(default, bool):
        own = st.booleans()
    elif isinstance(default, int):
        own = st.integers(min_value=-2, max_value=max(10, 4 * default))
    elif isinstance(default, float):
        own = st.floats(min_value=-1.0, max_value=max(10.0, 4 * default)) | st.sampled_from(
            [math.inf, math.nan])
    elif isinstance(param.check, OneOf):
        own = st.sampled_from([*param.check.choices, "no-such-choice"])
    else:
        own = paths | st.text(max_size=12)
    return st.one_of(st.just(default), own, own, values)


run_values = st.lists(st.sampled_from(NAMES), unique=True, max_size=6).flatmap(
    lambda names: st.fixed_dictionaries({name: typed_values(name) for name in names}))


@fuzz(300)
@given(chosen=run_values, unknown=st.dictionaries(st.text(max_size=12), values, max_size=1))
def test_the_graphs_check_never_raises_anything_but_a_parameter_error(chosen, unknown):
    chosen = {**unknown, **chosen}
    from sgim_nodes.graph.description import NODES, check, declared
    from sgim_ros.params import ParameterError

    try:
        checked = check(chosen)
    except ParameterError as error:
        _one_line_each(error)
        tally("description.check", "refused")
        return
    by_name = declared(NODES.values())
    for name, value in checked.items():
        for _spec, param in by_name[name]:
            _accepted_is_usable(param, value)
    tally("description.check", "accepted")


# --- parameter files --------------------------------------------------------------------------
yaml_scalars = st.one_of(st.none(), st.booleans(), st.integers(), st.floats(),
                         st.text(max_size=20))
yaml_documents = st.recursive(yaml_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)),
    max_leaves=12)


def _read(tmp_path: Path, content: bytes, target: str) -> None:
    from sgim_nodes.graph.overrides import read_parameter_files
    from sgim_ros.params import ParameterError

    path = tmp_path / "fuzz.yaml"
    path.write_bytes(content)
    try:
        read_parameter_files([path])
    except ParameterError as error:
        _one_line_each(error)
        assert "\n" not in str(error), str(error)
        tally(target, "refused")
        return
    tally(target, "accepted")


@fuzz(300)
@given(document=yaml_documents)
def test_random_yaml_documents_are_read_or_refused_in_one_line(tmp_path, document):
    _read(tmp_path, yaml.safe_dump(document).encode(), "parameter file: random YAML")


@fuzz(300)
@given(body=st.dictionaries(st.one_of(st.sampled_from(NAMES), st.text(max_size=8)),
                            yaml_documents, max_size=5),
       section=st.sampled_from(["/**", "sim_bridge", "/teacher", "/**/recorder", "nobody",
                                "/sim*"]))
def test_random_parameter_sections_are_read_or_refused_in_one_line(tmp_path, body, section):
    text = yaml.safe_dump({section: {"ros__parameters": body}})
    _read(tmp_path, text.encode(), "parameter file: random sections")


@fuzz(300)
@given(content=st.one_of(st.binary(max_size=200),
                         st.text(max_size=200).map(lambda t: t.encode("utf-8", "surrogatepass")),
                         st.text(alphabet="{}[]:,-&*!|>'\"#%@` \n\tab1.", max_size=80)
                         .map(str.encode)))
def test_random_bytes_are_refused_or_read_in_one_line(tmp_path, content):
    _read(tmp_path, content, "parameter file: random bytes")


@fuzz(200)
@given(names=st.lists(st.sampled_from(NAMES), min_size=1, max_size=6),
       repeat=st.integers(min_value=0, max_value=5), sections=st.booleans())
def test_a_key_given_twice_is_always_refused_naming_the_line_and_the_key(tmp_path, names,
                                                                       repeat, sections):
    """ROS and PyYAML keep the last of two equal keys without a word: always refused, with
    the file, the line and the key, whether a parameter or a whole section is repeated."""
    from sgim_nodes.graph.overrides import read_parameter_files
    from sgim_ros.params import ParameterError

    if sections:  # a section given twice: its parameters would silently replace the first's
        text = "/**:\n  ros__parameters:\n    a: 1\n/**:\n  ros__parameters:\n    b: 1\n"
        key, line, first = "/**", 4, 1
    else:
        names = [*names, names[repeat % len(names)]]
        text = "/**:\n  ros__parameters:\n" + "".join(f"    {n}: 1\n" for n in names)
        i = next(i for i, n in enumerate(names) if n in names[:i])  # the first repeat
        key, line, first = names[i], 3 + i, 3 + names.index(names[i])
    path = tmp_path / "twice.yaml"
    path.write_text(text)
    with pytest.raises(ParameterError) as refused:
        read_parameter_files([path])
    message = str(refused.value)
    assert "\n" not in message and str(path) in message
    assert f"line {line}: key '{key}' given twice (first at line {first})" in message, message
    tally("parameter file: duplicate keys", "refused")
