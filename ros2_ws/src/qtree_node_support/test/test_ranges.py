"""The one range checker (#27) and the descriptors declared with the same bounds."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st
from qtree_node_support.parameters import range_descriptor
from qtree_node_support.ranges import range_problem, setting_problem


@pytest.mark.parametrize(
    ('value', 'problem'),
    [
        (0.5, None),
        (0, None),
        (1, None),
        (True, 'must be a number'),
        ('0.5', 'must be a number'),
        (None, 'must be a number'),
        (math.nan, 'must be in [0, 1]'),
        (math.inf, 'must be in [0, 1]'),
        (-1e-9, 'must be in [0, 1]'),
        (1.0000001, 'must be in [0, 1]'),
    ],
)
def test_a_value_is_a_finite_number_inside_its_bounds(value: object, problem: str | None) -> None:
    assert range_problem(value, 0, 1) == problem


def test_an_integer_setting_refuses_fractions_and_nan() -> None:
    assert range_problem(3.0, 1, 10, integer=True) is None
    assert range_problem(3.5, 1, 10, integer=True) == 'must be an integer'
    assert range_problem(math.nan, 1, 10, integer=True) == 'must be an integer'
    assert range_problem(11, 1, 10, integer=True) == 'must be in [1, 10]'


@given(st.floats(allow_nan=True, allow_infinity=True), st.floats(-10, 10), st.floats(0, 10))
def test_the_checker_accepts_exactly_the_closed_interval(value: float, low: float, span: float):
    high = low + span
    accepted = range_problem(value, low, high) is None
    assert accepted == (math.isfinite(value) and low <= value <= high)


def test_the_descriptor_declares_the_same_bounds() -> None:
    floats = range_descriptor('gain [-]', 0.01, 0.5)
    assert floats.description == 'gain [-]' and not floats.integer_range
    assert (
        floats.floating_point_range[0].from_value,
        floats.floating_point_range[0].to_value,
    ) == (
        0.01,
        0.5,
    )
    ints = range_descriptor('restarts [count]', 0, 20)  # int bounds: an integer range
    assert (ints.integer_range[0].from_value, ints.integer_range[0].to_value) == (0, 20)
    assert ints.integer_range[0].step == 1 and not ints.floating_point_range
    forced = range_descriptor('rate [Hz]', 10, 1000, integer=False)
    assert forced.floating_point_range[0].to_value == 1000.0 and not forced.integer_range
    plain = range_descriptor('URDF', read_only=True)
    assert plain.read_only and not plain.floating_point_range and not plain.integer_range


def test_a_setting_is_looked_up_in_its_table_first() -> None:
    table = {'gain': (0.0, 1.0, 'gain [-]'), 'restarts': (0, 20, 'restarts [count]')}
    assert setting_problem(table, 'gain', 0.5, kind='planner') is None
    assert setting_problem(table, 'gian', 0.5, kind='planner') == 'unknown planner setting'
    assert setting_problem(table, 'gain', 2.0, kind='planner') == 'must be in [0.0, 1.0]'
    integers = {'restarts'}
    assert setting_problem(table, 'restarts', 2.5, kind='x', integer_fields=integers) == (
        'must be an integer'
    )
    assert setting_problem(table, 'restarts', 2.5, kind='x') is None
