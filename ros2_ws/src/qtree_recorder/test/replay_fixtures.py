"""Small synthetic qtree-tamp run logs for the reader, Rerun and replay tests (no rclpy).

Written through the recorder's own :class:`qtree_recorder.mcap_log.McapLog` (rosbag2
conventions: QoS metadata, ``rosbag2`` record, full definitions) with messages encoded from their
definition text, so the files look like what the recorder node writes.

Tests load this file by path (``--import-mode=importlib`` puts no test directory on
``sys.path``) under the module name ``qtree_recorder_replay_fixtures``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from qtree_recorder.encoding import DynamicEncoder
from qtree_recorder.mcap_log import McapLog
from qtree_recorder.qos import QosProfileData

T0_NS = 1_700_000_000_000_000_000  # first log time [ns since epoch]
JOINT_PERIOD_NS = 50_000_000  # /joint_states period [ns] (20 Hz)
HOME = (4.71, 2.84, 0.0, 0.75, 4.62, 4.48, 4.88)  # Jaco² "Home" [rad]
OBSTACLES = ('O1', 'O2', 'O3')
BEST_SEQUENCE = ('O2', 'T')


def joint_names(prefix: str = 'j2s7s300_') -> list[str]:
    """The 13 joint names of /joint_states (7 arm, 3 fingers, 3 finger tips)."""
    arm = [f'{prefix}joint_{i}' for i in range(1, 8)]
    fingers = [f'{prefix}joint_finger_{i}' for i in (1, 2, 3)]
    tips = [f'{prefix}joint_finger_tip_{i}' for i in (1, 2, 3)]
    return arm + fingers + tips


def _stamp(t_ns: int) -> dict[str, int]:
    return {'sec': t_ns // 1_000_000_000, 'nanosec': t_ns % 1_000_000_000}


def _pose(x: float, y: float, z: float) -> dict[str, Any]:
    return {
        'position': {'x': x, 'y': y, 'z': z},
        'orientation': {'x': 0.0, 'y': 0.0, 'z': 0.0, 'w': 1.0},
    }


def _object(oid: str, role: int, pos: tuple[float, float, float], status: int) -> dict[str, Any]:
    box = role == 2
    return {
        'id': oid,
        'role': role,
        'shape': {
            'type': 1 if box else 3,  # SolidPrimitive.BOX, .CYLINDER
            'dimensions': [0.7, 1.0, 0.04] if box else [0.15, 0.03],
            'polygon': {'points': []},
        },
        'pose': _pose(*pos),
        'status': status,
    }


def scene_message(
    t_ns: int, relocated: tuple[str, ...] = (), moved: dict[str, tuple] | None = None
) -> dict[str, Any]:
    """A Scene: table, target T, obstacles O1..O3 (the relocated ones in the drop zone;
    ``moved``: ids in the clutter at another position [m])."""
    objects = [_object('table', 2, (0.5, 0.1, -0.02), 0), _object('T', 0, (0.6, 0.0, 0.075), 0)]
    for index, oid in enumerate(OBSTACLES):
        y = -0.12 + 0.12 * index
        if oid in relocated:
            objects.append(_object(oid, 1, (0.3 + 0.07 * index, 0.45, 0.075), 2))
        else:
            objects.append(_object(oid, 1, (moved or {}).get(oid, (0.48, y, 0.075)), 0))
    return {
        'header': {'stamp': _stamp(t_ns), 'frame_id': 'j2s7s300_link_base'},
        'scenario_name': 'fixture',
        'objects': objects,
        'attached_id': '',
        'drop_zone': _pose(0.37, 0.45, 0.005),
        'drop_zone_size': {'x': 0.3, 'y': 0.25, 'z': 0.01},
        'robot_base': _pose(0.0, 0.0, 0.0),
    }


def _event(t_ns: int, oid: str, relocated: list[str], feasible: bool) -> dict[str, Any]:
    poses = [_pose(0.3 + 0.02 * k, -0.2 + 0.04 * k, 0.3 - 0.01 * k) for k in range(8)]
    return {
        'stamp': _stamp(t_ns),
        'object_id': oid,
        'relocated_ids': relocated,
        'execute': False,
        'feasible': feasible,
        'reason': 0 if feasible else 205,
        'message': 'ok' if feasible else 'scene collision',
        'planning_time': 0.12,
        'from_cache': False,
        'ee_path': {'header': {'stamp': _stamp(t_ns), 'frame_id': 'j2s7s300_link_base'},
                    'poses': poses},
    }  # fmt: skip


def _qtree(t_ns: int, episode: int) -> dict[str, Any]:
    nodes = ['', 'O1', 'O2', 'O2,T']
    edges = [
        {'parent': 0, 'child': 1, 'object_id': 'O1', 'q': -0.5, 'reward': -1.0,
         'on_best_path': False},
        {'parent': 0, 'child': 2, 'object_id': 'O2', 'q': 0.81, 'reward': 0.0,
         'on_best_path': True},
        {'parent': 2, 'child': 3, 'object_id': 'T', 'q': 0.9 + 0.01 * episode, 'reward': 1.0,
         'on_best_path': True},
    ]  # fmt: skip
    return {'stamp': _stamp(t_ns), 'episode': episode, 'node_sequences': nodes, 'edges': edges}


def _stats(t_ns: int, episode: int) -> dict[str, Any]:
    return {
        'stamp': _stamp(t_ns),
        'policy': 'H-eG',
        'episode': episode,
        'nodes': 2 + episode,
        'edges': 1 + episode,
        'mp_calls': 1 + episode,
        'planner_runs': 1 + episode,
        'q_bar': 0.5 * episode,
        'epsilon': 0.9**episode,
        'episode_sequence': ['O2', 'T'],
        'reached_target': True,
        'best_sequence': list(BEST_SEQUENCE),
    }


@dataclass(frozen=True)
class FixtureCounts:
    """How many messages :func:`write_run` wrote per topic."""

    joint_states: int
    scene: int
    events: int
    qtree: int
    training_stats: int


def _write_world(put: Any, t_ns: int, latched: Any, default: Any) -> None:
    """O3 moves 0.1 m in the clutter while T is carried, the planner answers SCENE_CHANGED and
    the task planner re-plans (#32)."""
    moved = {'O3': (0.48, 0.22, 0.075)}
    put('/scene', 'qtree_msgs/msg/Scene', scene_message(t_ns + 10, ('O2',), moved), t_ns + 10,
        latched)  # fmt: skip
    event = _event(t_ns + 20, 'T', ['O2'], False) | {
        'execute': True,
        'reason': 304,
        'message': "'O3' moved 0.100 m; undone",
    }
    put('/motion_planner/events', 'qtree_msgs/msg/PlanningEvent', event, t_ns + 20, default)
    base = {'cause': "SCENE_CHANGED relocating 'T': 'O3' moved 0.100 m", 'kept_ids': ['O2']}
    started = base | {
        'stamp': _stamp(t_ns + 30),
        'replan': 1,
        'phase': 'started',
        'sequence': [],
        'reused_answers': -1,
        'planner_runs': -1,
    }
    planned = base | {
        'stamp': _stamp(t_ns + 40),
        'replan': 1,
        'phase': 'planned',
        'sequence': ['O3', 'T'],
        'reused_answers': 3,
        'planner_runs': 2,
    }
    for k, msg in enumerate((started, planned)):
        put('/task_planner/replans', 'qtree_msgs/msg/ReplanEvent', msg, t_ns + 30 + 10 * k,
            default)  # fmt: skip


def write_run(
    path: Path,
    *,
    joint_states: int = 20,
    episodes: int = 4,
    robot_prefix: str = 'j2s7s300_',
    urdf_text: str | None = None,
    chunk_size: int = 256 * 1024,
    close: bool = True,
    world: bool = False,
) -> FixtureCounts:
    """Write a small run log.

    Args:
        path: output ``.mcap``.
        joint_states: number of /joint_states messages (20 Hz).
        episodes: number of /training_stats and /qtree messages.
        robot_prefix: joint name prefix (another value makes a log of "another robot").
        urdf_text: URDF for /robot_description (not written when None).
        chunk_size: MCAP chunk size [bytes]; small values give many chunks.
        close: False leaves the file without summary and footer (like a killed recorder).
        world: also a changing world (#32) after the relocation of O2: O3 moved in the clutter
            (a /scene), the SCENE_CHANGED answer relocating T and the re-plan's two
            /task_planner/replans events.
    """
    encoder = DynamicEncoder()
    log = McapLog(path, chunk_size=chunk_size, flush_interval_s=1e9)
    latched = (QosProfileData.transient_local(),)
    default = (QosProfileData(),)

    def put(topic: str, type_name: str, msg: dict[str, Any], t_ns: int, qos: Any) -> None:
        log.write(topic, type_name, encoder.encode(type_name, msg), t_ns, qos)

    log.add_metadata('qtree_run', {'scenario': 'fixture', 'policy': 'H-eG', 'seed': '7'})
    if urdf_text is not None:
        put('/robot_description', 'std_msgs/msg/String', {'data': urdf_text}, T0_NS, latched)
    put('/scene', 'qtree_msgs/msg/Scene', scene_message(T0_NS), T0_NS, latched)
    names = joint_names(robot_prefix)
    events = 0
    for k in range(joint_states):
        t_ns = T0_NS + (k + 1) * JOINT_PERIOD_NS
        phase = k / max(1, joint_states - 1)
        arm = [q + 0.4 * math.sin(math.pi * phase) * (i % 2) for i, q in enumerate(HOME)]
        state = {
            'header': {'stamp': _stamp(t_ns), 'frame_id': ''},
            'name': names,
            'position': arm + [0.2 + 0.8 * phase] * 3 + [0.1] * 3,
            'velocity': [],
            'effort': [],
        }
        put('/joint_states', 'sensor_msgs/msg/JointState', state, t_ns, default)
        if k < episodes:
            oid = OBSTACLES[k % len(OBSTACLES)]
            put('/motion_planner/events', 'qtree_msgs/msg/PlanningEvent',
                _event(t_ns, oid, [], k % 2 == 1), t_ns + 1, default)  # fmt: skip
            put('/qtree', 'qtree_msgs/msg/QTree', _qtree(t_ns, k), t_ns + 2, latched)
            put('/training_stats', 'qtree_msgs/msg/TrainingStats', _stats(t_ns, k), t_ns + 3,
                default)  # fmt: skip
            events += 1
    t_end = T0_NS + (joint_states + 1) * JOINT_PERIOD_NS
    put('/scene', 'qtree_msgs/msg/Scene', scene_message(t_end, ('O2',)), t_end, latched)
    if world:
        _write_world(put, t_end, latched, default)
    if close:
        log.close()
    else:  # like a killed recorder: chunks on disk, no summary, no footer
        log.flush()
        log._file.close()
    return FixtureCounts(joint_states, 2, events, events, events)


def rrd_chunks(path: Path) -> list[Any]:
    """Every chunk of a saved ``.rrd`` (``rerun.chunk``: entity_path, to_record_batch())."""
    from rerun.chunk import RrdReader

    return list(RrdReader(str(path)).store().stream())


def rrd_entities(path: Path) -> set[str]:
    """Entity paths that hold data in a saved ``.rrd``."""
    return {chunk.entity_path for chunk in rrd_chunks(path) if chunk.num_rows}


def rrd_column(path: Path, entity: str, column: str) -> list[Any]:
    """All values of ``column`` (e.g. ``'Transform3D:translation'``) logged to ``entity``."""
    values: list[Any] = []
    for chunk in rrd_chunks(path):
        if chunk.entity_path != entity:
            continue
        batch = chunk.to_record_batch()
        if column in batch.schema.names:
            values += [v for v in batch.column(column).to_pylist() if v is not None]
    return values
