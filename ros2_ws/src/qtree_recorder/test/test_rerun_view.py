"""Tests of RunView: what lands in a saved .rrd, joint maths, robustness, layout (no rclpy)."""

from __future__ import annotations

import importlib.util
import logging
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from qtree_recorder import rerun_blueprint as bp
from qtree_recorder.rerun_view import REASONS, RunView


def _load_fixtures():
    name = 'qtree_recorder_replay_fixtures'
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            name, Path(__file__).with_name(f'{name[15:]}.py')
        )
        sys.modules[name] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(sys.modules[name])
    return sys.modules[name]


FX = _load_fixtures()
T_NS = FX.T0_NS


def _scene() -> list[dict]:
    return [
        {'id': 'table', 'role': 'static', 'shape': 'box', 'status': 'in_clutter',
         'size': (0.7, 1.0, 0.04), 'position': (0.5, 0.1, -0.02), 'orientation': (0, 0, 0, 1)},
        {'id': 'T', 'role': 'target', 'shape': 'cylinder', 'status': 'in_clutter',
         'radius': 0.03, 'height': 0.15, 'position': (0.6, 0.0, 0.075),
         'orientation': (0, 0, 0, 1)},
        {'id': 'O1', 'role': 'obstacle', 'shape': 'cylinder', 'status': 'relocated',
         'radius': 0.03, 'height': 0.15, 'position': (0.3, 0.45, 0.075),
         'orientation': (0, 0, 0, 1)},
    ]  # fmt: skip


@pytest.fixture
def urdf() -> Path:
    from jaco2_description.model import urdf_path

    return urdf_path()


def test_saved_rrd_holds_every_part_of_the_view(tmp_path: Path, urdf: Path) -> None:
    rrd = tmp_path / 'run.rrd'
    view = RunView(mode='save', rrd_path=rrd, urdf_path=urdf)
    names = FX.joint_names()
    view.on_joint_state(names, [*FX.HOME] + [0.2] * 6, T_NS)
    view.on_scene(_scene(), T_NS, drop_zone=((0.37, 0.45, 0.0), (0.3, 0.25, 0.01)))
    view.on_ee_path('O1', np.tile([0.3, 0.1, 0.3, 0, 0, 0, 1.0], (5, 1)), True, T_NS)
    view.on_planning_event('O1', [], False, 'SCENE_COLLISION', T_NS, planning_time_s=0.1)
    view.on_qtree(['', 'O1', 'O1,T'], [(0, 1, 'O1', 0.5, True), (1, 2, 'T', 1.0, True)], 3)
    view.on_training_stats(3, 1.5, 3, 2, 2, 0.5, T_NS)
    view.close()
    assert view.error_count == 0
    entities = FX.rrd_entities(rrd)
    expected = {
        '/j2s7s300/visual_geometries/j2s7s300_link_base/visual_0',
        '/tf/j2s7s300_joint_1', '/tf/j2s7s300_joint_7', '/tf/j2s7s300_joint_finger_tip_3',
        '/scene/objects/table', '/scene/objects/T', '/scene/objects/O1', '/scene/drop_zone',
        '/plans/O1', '/events', '/qtree/nodes', '/qtree/edges', '/qtree/note',
        '/stats/q_bar', '/stats/nodes', '/stats/edges', '/stats/mp_calls', '/stats/epsilon',
    }  # fmt: skip
    assert expected <= entities, expected - entities
    labels = FX.rrd_column(rrd, '/qtree/nodes', 'Points2D:labels')
    assert labels == [['s_H (episode 3)', 'O1 Q=+0.5', 'T Q=+1.0']]
    assert len(FX.rrd_column(rrd, '/qtree/edges', 'LineStrips2D:strips')[0]) == 2
    assert FX.rrd_column(rrd, '/stats/q_bar', 'Scalars:scalars') == [[1.5]]
    colors = FX.rrd_column(rrd, '/scene/objects/O1', 'Cylinders3D:colors')
    assert colors and colors[-1][0] != FX.rrd_column(rrd, '/scene/objects/T',
                                                     'Cylinders3D:colors')[-1][0]  # fmt: skip


def test_joint_transforms_equal_the_kinematic_model(tmp_path: Path, urdf: Path) -> None:
    """Each logged joint transform is the parent→child placement Pinocchio computes (at Home)."""
    from jaco2_description.model import link_placements

    rrd = tmp_path / 'joints.rrd'
    view = RunView(mode='save', rrd_path=rrd, urdf_path=urdf)
    names = FX.joint_names()
    positions = [*FX.HOME, 0.7, 0.7, 0.7, 0.3, 0.3, 0.3]
    view.on_joint_state(names, positions, T_NS)
    view.close()
    placements = link_placements(dict(zip(names, positions, strict=True)))
    for index in range(1, 8):
        entity = f'/tf/j2s7s300_joint_{index}'
        child = FX.rrd_column(rrd, entity, 'Transform3D:child_frame')[0][0]
        translation = np.array(FX.rrd_column(rrd, entity, 'Transform3D:translation')[0][0])
        x, y, z, w = FX.rrd_column(rrd, entity, 'Transform3D:quaternion')[0][0]
        expected = placements[child]
        np.testing.assert_allclose(translation, expected.translation, atol=1e-5)
        rotation = _quaternion_matrix(x, y, z, w)
        np.testing.assert_allclose(rotation, expected.rotation, atol=1e-5)


def _quaternion_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def test_errors_are_swallowed_and_reported_once(caplog: pytest.LogCaptureFixture) -> None:
    view = RunView(mode='memory')
    with caplog.at_level(logging.WARNING):
        view.on_scene([{'id': 'broken'}], T_NS)  # no position: the conversion fails
        view.on_scene([{'id': 'broken'}], T_NS)
        view.on_ee_path('O1', 'not a path', True, T_NS)
    assert view.error_count == 3
    reports = [r.getMessage() for r in caplog.records]
    assert sum('on_scene failed' in r for r in reports) == 1
    assert sum('on_ee_path failed' in r for r in reports) == 1
    view.on_training_stats(0, 0.0, 1, 0, 0, 1.0, T_NS)  # the view keeps working
    assert view.error_count == 3
    view.close()


def test_joint_state_without_robot_is_ignored() -> None:
    view = RunView(mode='memory')
    assert not view.has_robot
    view.on_joint_state(['j2s7s300_joint_1'], [1.0], T_NS)
    assert view.error_count == 0


def test_constructor_rejects_bad_modes(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match='rrd_path'):
        RunView(mode='save')
    with pytest.raises(ValueError, match='unknown'):
        RunView(mode='web', rrd_path=tmp_path / 'x.rrd')  # type: ignore[arg-type]


def test_tree_layout_puts_children_below_and_apart() -> None:
    edges = [(0, 1), (0, 2), (1, 3), (1, 4), (2, 5)]
    positions = bp.tree_layout(6, edges)
    for parent, child in edges:
        assert positions[child, 1] == positions[parent, 1] + bp.LEVEL_SPACING
    leaves = positions[[3, 4, 5], 0]
    assert len(set(leaves)) == 3
    assert positions[1, 0] == pytest.approx((positions[3, 0] + positions[4, 0]) / 2)


def test_reason_names_match_the_service_definition() -> None:
    from ament_index_python.packages import get_package_share_directory

    srv = Path(get_package_share_directory('qtree_msgs')) / 'srv' / 'RelocateObject.srv'
    constants = dict(
        (int(value), name) for name, value in re.findall(r'uint16 (\w+)=(\d+)', srv.read_text())
    )
    assert constants == REASONS


def test_tracking_shows_reference_and_actual_paths_and_the_error(tmp_path: Path) -> None:
    from types import SimpleNamespace as Ns

    def point(x, y, z):
        return Ns(position=Ns(x=x, y=y, z=z))

    rrd = tmp_path / 'tracking.rrd'
    view = RunView(mode='save', rrd_path=rrd)
    for k in range(60):
        msg = Ns(object_id='O2', phase='tracking' if k < 59 else 'done', message='',
                 ee_reference=point(0.3 + 0.01 * k, 0.0, 0.2),
                 ee_measured=point(0.3 + 0.01 * k, 0.002, 0.2), error_m=0.002)  # fmt: skip
        assert view.on_message('/motion_planner/tracking', msg, T_NS + k * 10_000_000)
    stop = Ns(object_id='O2', phase='stopped', message='closed loop stopped: intruder',
              ee_reference=point(0, 0, 0), ee_measured=point(0, 0, 0), error_m=0.0)  # fmt: skip
    view.on_message('/motion_planner/tracking', stop, T_NS + 700_000_000)
    view.close()
    assert view.error_count == 0
    entities = FX.rrd_entities(rrd)
    pieces = {
        '/tracking/O2/reference/0000',
        '/tracking/O2/actual/0000',
        '/tracking/O2/actual/0001',
    }
    assert pieces | {'/tracking/error_mm'} <= entities
    errors = FX.rrd_column(rrd, '/tracking/error_mm', 'Scalars:scalars')
    assert len(errors) == 60 and abs(errors[0][0] - 2.0) < 1e-9
    first = FX.rrd_column(rrd, '/tracking/O2/actual/0000', 'LineStrips3D:strips')[0][0]
    second = FX.rrd_column(rrd, '/tracking/O2/actual/0001', 'LineStrips3D:strips')[0][0]
    assert len(first) == 50 and len(second) == 11  # pieces join: 50 + 10 new ticks + 1 shared
    assert first[-1] == second[0]
