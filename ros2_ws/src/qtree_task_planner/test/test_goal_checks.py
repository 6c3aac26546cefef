"""RetrieveTarget goal validation: every bad field is named in the error."""

import math

import pytest
from qtree_task_planner.exceptions import InvalidParameterError, UnknownPolicyError
from qtree_task_planner.goal_checks import FLOAT_FIELDS, settings_from_goal


def test_defaults_are_the_papers(make_goal) -> None:
    settings = settings_from_goal(make_goal(policy='h-εg', seed=7))
    config = settings.config
    assert (config.policy, config.alpha, config.gamma, config.max_episodes) == (
        'H-EG',
        0.5,
        0.9,
        5000,
    )
    assert config.seed == 7 and settings.feedback_every == 10 and not settings.execute


@pytest.mark.parametrize(
    ('field', 'value'),
    [
        ('alpha', 0.0),
        ('alpha', 1.01),
        ('gamma', 0.0),
        ('gamma', 2.0),
        ('epsilon0', 0.0),
        ('epsilon0', 1.5),
        ('epsilon_min', 0.0),
        ('epsilon_min', 1.1),
        ('max_episodes', 0),
        ('max_episodes', -3),
        ('beta', 0.0),
        ('beta', -1.0),
        ('feedback_every', 0),
        ('steady_episodes', 0),
        ('seed', -1),
    ],
)
def test_bad_fields_are_named(field: str, value: float, make_goal) -> None:
    with pytest.raises(InvalidParameterError, match=f'invalid {field}='):
        settings_from_goal(make_goal(**{field: value}))


def test_epsilon_min_above_epsilon0(make_goal) -> None:
    with pytest.raises(InvalidParameterError, match=r'epsilon_min.*epsilon0'):
        settings_from_goal(make_goal(epsilon0=0.1, epsilon_min=0.2))


def test_unknown_policy(make_goal) -> None:
    with pytest.raises(UnknownPolicyError, match=r"invalid policy='SARSA'.*H-EG-SET"):
        settings_from_goal(make_goal(policy='SARSA'))


@pytest.mark.parametrize('value', [math.inf, -math.inf, math.nan], ids=['inf', '-inf', 'nan'])
@pytest.mark.parametrize('field', FLOAT_FIELDS)
def test_every_non_finite_float_field_is_named(field: str, value: float, make_goal) -> None:
    with pytest.raises(InvalidParameterError, match=f'invalid {field}=.*finite') as err:
        settings_from_goal(make_goal(**{field: value}))  # beta=inf was accepted (#18)
    assert err.value.field == field


def test_the_float_fields_are_every_float64_of_the_goal() -> None:
    from qtree_msgs.action import RetrieveTarget

    types = RetrieveTarget.Goal.get_fields_and_field_types()
    assert set(FLOAT_FIELDS) == {name for name, kind in types.items() if kind == 'double'}


def test_a_huge_policy_is_quoted_short(make_goal) -> None:
    with pytest.raises(UnknownPolicyError, match=r'\(10000 characters\)') as err:
        settings_from_goal(make_goal(policy='P' * 10_000))  # was echoed in full (#18)
    assert len(str(err.value)) < 300


def test_max_replans_defaults_to_3_and_is_bounded(make_goal) -> None:
    assert settings_from_goal(make_goal()).max_replans == 3
    assert settings_from_goal(make_goal(max_replans=0)).max_replans == 0
    without = make_goal()
    del without.max_replans  # a goal object without the field (an older client)
    assert settings_from_goal(without).max_replans == 3
    with pytest.raises(InvalidParameterError, match='max_replans'):
        settings_from_goal(make_goal(max_replans=101))
