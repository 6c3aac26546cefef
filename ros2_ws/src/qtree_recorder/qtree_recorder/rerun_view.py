"""Log one qtree-tamp run to Rerun from plain Python data (live recorder and offline replay).

The arm comes from its URDF through Rerun's own loader and moves by one ``Transform3D`` per joint
(parent/child link frames, ``rr.urdf.UrdfJoint.compute_transform``). Scene objects, planned
end-effector paths, the Q-tree graph, episode curves and planning events go to the entities of
:mod:`qtree_recorder.rerun_blueprint`; the changing world (#32: scene events, SCENE_CHANGED /
GRASP_FAILED answers, re-plans from ``/task_planner/replans``, :mod:`.world_changes`) goes to
``/events/world`` as text on the same timeline. Every ``on_*`` method swallows Rerun errors
(logged once per method): the caller, e.g. the recorder node, must keep recording whatever
Rerun does.

Scene objects are dicts with the keys (lengths [m], angles via unit quaternions)::

    id: str; role: 'target' | 'obstacle' | 'static'; shape: 'cylinder' | 'box';
    status: 'in_clutter' | 'grasped' | 'relocated'; radius: float; height: float;
    size: (3,) full box edges; position: (3,) centre; orientation: (4,) quaternion x, y, z, w

:meth:`RunView.on_message` takes decoded ROS messages (rclpy or ``mcap_ros2``; only attribute
access is used) of the graph's topics and makes these calls, so live and replayed runs look alike.
"""

from __future__ import annotations

import functools
import logging
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Literal, TypeVar

import numpy as np
import rerun as rr

from qtree_recorder import rerun_blueprint as bp
from qtree_recorder.markers import object_geometry
from qtree_recorder.qtree_figure import (
    DEFAULT_TOP_K,
    KIND_FEASIBLE,
    KIND_INFEASIBLE,
    KIND_TARGET,
    layout_tree,
)
from qtree_recorder.world_changes import REPLAN_TOPIC, WorldChanges

_LOG = logging.getLogger(__name__)
EVENTS_STOP = f'{bp.EVENTS_ENTITY}/execution'  # closed-loop stops in the event log

# Colours [RGB 0..255] by role, and for relocated objects.
ROLE_COLORS = {'target': (40, 180, 70), 'obstacle': (210, 50, 50), 'static': (139, 94, 60)}
RELOCATED_COLOR = (150, 150, 150)
GRASPED_COLOR = (250, 200, 40)
PATH_COLORS = {True: (40, 120, 230), False: (230, 120, 30)}  # feasible / infeasible
NODE_COLOR = (120, 120, 130)
HIGHLIGHT_COLOR = (255, 127, 14)  # the extracted sequence
EDGE_COLORS = {KIND_FEASIBLE: (150, 150, 160), KIND_INFEASIBLE: (214, 39, 40),
               KIND_TARGET: (44, 160, 44)}  # fmt: skip
ROOT_LABEL = 's_H'
QTREE_TOP_K = DEFAULT_TOP_K  # Q-tree view: nodes kept per level (as the PNG)
QTREE_X_SPACING = 175.0  # Q-tree view: distance between neighbouring leaves [view units]
QTREE_Y_SPACING = 110.0  # Q-tree view: distance between levels [view units]
# qtree_msgs constants (ObjectState.msg, RelocateObject.srv) as names.
ROLES = {0: 'target', 1: 'obstacle', 2: 'static'}
STATUSES = {0: 'in_clutter', 1: 'grasped', 2: 'relocated'}
REASONS = {
    0: 'SUCCESS', 101: 'UNKNOWN_OBJECT', 102: 'ALREADY_RELOCATED', 103: 'INVALID_REQUEST',
    104: 'NO_SCENE', 105: 'INVALID_SCENE', 201: 'NO_CARTESIAN_PATH', 202: 'IK_NOT_CONVERGED',
    203: 'JOINT_LIMIT', 204: 'SELF_COLLISION', 205: 'SCENE_COLLISION',
    206: 'VERIFICATION_FAILED', 207: 'NO_PLACEMENT', 208: 'OBJECT_TOO_BIG',
    209: 'CARRIED_COLLISION', 301: 'TIMEOUT', 302: 'EXECUTION_FAILED', 303: 'PLANNER_BUSY',
    304: 'SCENE_CHANGED', 305: 'GRASP_FAILED',
}  # fmt: skip
TOPICS = ('/robot_description', '/joint_states', '/scene', '/motion_planner/events', '/qtree',
          '/training_stats', '/motion_planner/tracking', REPLAN_TOPIC)  # fmt: skip
WORLD_ENTITY = f'{bp.EVENTS_ENTITY}/world'  # scene events and re-plans (#32) on the timeline
TRACK_COLORS = {'reference': (120, 120, 130), 'actual': (40, 180, 70)}
TRACK_EVERY = 50  # log the reference / actual EE paths in pieces of this many ticks [-]

F = TypeVar('F', bound=Callable[..., Any])


def _guarded(method: F) -> F:
    """Run ``method``; log its first exception (per method) and swallow every exception."""

    @functools.wraps(method)
    def wrapper(self: RunView, *args: Any, **kwargs: Any) -> Any:
        try:
            return method(self, *args, **kwargs)
        except Exception as err:  # the view must never break the caller
            self.error_count += 1
            if method.__name__ not in self._reported:
                self._reported.add(method.__name__)
                _LOG.warning('Rerun view: %s failed (%s); further errors not reported',
                             method.__name__, err)  # fmt: skip
            return None

    return wrapper  # type: ignore[return-value]


class RunView:
    """One run logged to its own Rerun recording stream.

    Args:
        mode: ``'save'`` writes ``rrd_path``; ``'spawn'`` starts (or connects to) a viewer;
            ``'memory'`` keeps everything in memory (tests).
        rrd_path: output file for ``'save'``.
        application_id: Rerun application id.
        urdf_path: robot URDF to log at once (else call :meth:`on_robot_description`).
        recording_id: Rerun recording id (a fresh one when None).

    Raises:
        ValueError: ``'save'`` without ``rrd_path`` or an unknown mode.

    Attributes:
        error_count: number of swallowed Rerun errors.
    """

    def __init__(
        self,
        *,
        mode: Literal['save', 'spawn', 'memory'],
        rrd_path: Path | None = None,
        application_id: str = 'qtree_tamp',
        urdf_path: Path | None = None,
        recording_id: str | None = None,
    ) -> None:
        if mode not in ('save', 'spawn', 'memory'):
            raise ValueError(f'unknown Rerun mode {mode!r}')
        if mode == 'save' and rrd_path is None:
            raise ValueError("mode 'save' needs rrd_path")
        self.error_count = 0
        self._reported: set[str] = set()
        self._urdf: rr.urdf.UrdfTree | None = None
        self._objects: set[str] = set()
        self._tmpdir: tempfile.TemporaryDirectory[str] | None = None
        self._track: dict[str, list] = {'id': [''], 'reference': [], 'actual': [], 'chunk': [0]}
        self._world = WorldChanges()  # scene events and re-plans (#32)
        self.rec = rr.RecordingStream(application_id, recording_id=recording_id)
        self.rec.set_log_time_enabled(False)  # wall time of logging: meaningless in a replay
        blueprint = bp.default_blueprint()
        if rrd_path is not None and mode == 'save':
            Path(rrd_path).parent.mkdir(parents=True, exist_ok=True)
            self.rec.save(rrd_path, default_blueprint=blueprint)
        elif mode == 'spawn':
            self.rec.spawn(default_blueprint=blueprint)
        else:
            self.memory = self.rec.memory_recording()
            self.rec.send_blueprint(blueprint)
        bp.log_series_styles(self.rec)
        if urdf_path is not None:
            self.on_robot_description(Path(urdf_path))

    @property
    def has_robot(self) -> bool:
        """True once a URDF was logged."""
        return self._urdf is not None

    def _set_time(self, t_ns: int | None, episode: int | None = None) -> None:
        self.rec.reset_time()
        if t_ns is not None:
            self.rec.set_time(bp.TIME_TIMELINE, timestamp=np.datetime64(int(t_ns), 'ns'))
        if episode is not None:
            self.rec.set_time(bp.EPISODE_TIMELINE, sequence=int(episode))

    @_guarded
    def on_robot_description(self, urdf: Path | str) -> None:
        """Log the robot from a URDF file path (once; later calls are ignored).

        Args:
            urdf: path of the URDF file.
        """
        if self._urdf is not None:
            return
        self.rec.log_file_from_path(Path(urdf), static=True)
        self._urdf = rr.urdf.UrdfTree.from_file_path(Path(urdf))

    @_guarded
    def on_joint_state(self, names: Sequence[str], positions: Sequence[float], t_ns: int) -> None:
        """Move the arm: one ``Transform3D`` (parent → child link) per known joint.

        Args:
            names: joint names (joints not in the URDF are ignored).
            positions: joint angles [rad], same length as ``names``.
            t_ns: time [ns since epoch].
        """
        if self._urdf is None:
            return
        self._set_time(t_ns)
        for name, value in zip(names, positions, strict=False):
            joint = self._urdf.get_joint_by_name(name)
            if joint is None or joint.joint_type == 'fixed':
                continue
            self.rec.log(f'tf/{name}', joint.compute_transform(float(value), clamp=False))

    @_guarded
    def on_scene(
        self,
        objects: Sequence[dict[str, Any]],
        t_ns: int,
        *,
        drop_zone: tuple[Sequence[float], Sequence[float]] | None = None,
    ) -> None:
        """Draw the table and objects, coloured by role and status (see module docstring).

        Args:
            objects: scene objects as dicts (keys in the module docstring).
            t_ns: time [ns since epoch].
            drop_zone: ``(centre (3,), full size (3,))`` [m] of the drop zone, if any.
        """
        self._set_time(t_ns)
        current = set()
        for obj in objects:
            oid = str(obj['id'])
            current.add(oid)
            self.rec.log(f'{bp.SCENE_ENTITY}/objects/{oid}', *_object_archetypes(obj))
        for gone in self._objects - current:
            self.rec.log(f'{bp.SCENE_ENTITY}/objects/{gone}', rr.Clear(recursive=False))
        self._objects = current
        if drop_zone is not None:
            centre, size = drop_zone
            self.rec.log(
                f'{bp.SCENE_ENTITY}/drop_zone',
                rr.Boxes3D(centers=[centre], sizes=[size], colors=[(90, 90, 200)],
                           fill_mode='majorwireframe', labels=['drop zone']),
                rr.CoordinateFrame(bp.WORLD_FRAME),
            )  # fmt: skip

    @_guarded
    def on_ee_path(self, object_id: str, poses: Any, feasible: bool, t_ns: int) -> None:
        """Draw a planned Cartesian end-effector path for relocating ``object_id``.

        Args:
            object_id: the object the path relocates.
            poses: waypoints, shape (M, 7): x, y, z [m], qx, qy, qz, qw (or (M, 3)).
            feasible: whether the STPIK check passed (colour).
            t_ns: time [ns since epoch].
        """
        points = np.asarray(poses, dtype=float).reshape(-1, np.shape(poses)[-1])[:, :3]
        self._set_time(t_ns)
        entity = f'{bp.PLANS_ENTITY}/{object_id}'
        if len(points) < 2:
            self.rec.log(entity, rr.Clear(recursive=False))
            return
        label = f'{object_id} {"feasible" if feasible else "infeasible"}'
        self.rec.log(
            entity,
            rr.LineStrips3D([points], colors=[PATH_COLORS[bool(feasible)]], radii=[0.004],
                            labels=[label]),
            rr.CoordinateFrame(bp.WORLD_FRAME),
        )  # fmt: skip

    @_guarded
    def on_planning_event(
        self,
        object_id: str,
        relocated_ids: Sequence[str],
        feasible: bool,
        reason: str,
        t_ns: int,
        *,
        planning_time_s: float = 0.0,
        from_cache: bool = False,
        execute: bool = False,
        message: str = '',
    ) -> None:
        """Append one motion-planner query to the text log.

        Args:
            object_id: the object to relocate.
            relocated_ids: objects already relocated (the Q-tree node).
            feasible: the planner's answer.
            reason: reason name or code, e.g. ``'SCENE_COLLISION'``.
            t_ns: time [ns since epoch].
            planning_time_s: planning wall time [s].
            from_cache: answered from the planner's cache.
            execute: the motion was executed on the arm.
            message: the planner's free-text message.
        """
        self._set_time(t_ns)
        done = ','.join(relocated_ids) or '∅'
        verb = 'EXECUTE' if execute else 'plan'
        text = (
            f'{verb} {object_id} after [{done}]: {"feasible" if feasible else "infeasible"} '
            f'({reason}, {planning_time_s * 1e3:.0f} ms{", cached" if from_cache else ""})'
        )
        if message:
            text += f' {message}'
        level = rr.TextLogLevel.INFO if feasible else rr.TextLogLevel.WARN
        self.rec.log(bp.EVENTS_ENTITY, rr.TextLog(text, level=level))

    @_guarded
    def on_qtree(
        self,
        node_sequences: Sequence[str],
        edges: Sequence[tuple],
        episode: int,
        t_ns: int | None = None,
    ) -> None:
        """Draw the Q-tree like the paper's Figure 3 (:mod:`qtree_recorder.qtree_figure`).

        Levels are rows, the top ``QTREE_TOP_K`` nodes per level by Q are kept (the extracted
        path always), each node is labelled with its incoming action and Q, edges are grey
        (obstacle relocated), red (infeasible) or green (target), the extracted sequence
        orange and thick; a note above the root says what was left out.

        Args:
            node_sequences: node i's relocated sequence (ids joined by ','; node 0 = root '').
            edges: ``(parent, child, object_id, q, on_best_path[, reward])`` per edge.
            episode: training episode of this snapshot.
            t_ns: time [ns since epoch], if known.
        """
        self._set_time(t_ns, episode)
        drawing = layout_tree(node_sequences, edges, top_k=QTREE_TOP_K)
        order = sorted(drawing.positions)
        scale = np.array([QTREE_X_SPACING, QTREE_Y_SPACING])
        xy = {n: np.asarray(drawing.positions[n], dtype=float) * scale for n in order}
        incoming = {e.child: e for e in drawing.edges if e.tree_edge}
        on_path = set(drawing.path)

        def node_color(n: int) -> tuple[int, int, int]:
            if n in on_path:
                return HIGHLIGHT_COLOR
            edge = incoming.get(n)
            return EDGE_COLORS[edge.kind] if edge is not None else NODE_COLOR

        labels = [
            f'{incoming[n].object_id} Q={incoming[n].q:+.1f}'
            if n in incoming
            else f'{ROOT_LABEL} (episode {episode})'
            for n in order
        ]
        self.rec.log(
            f'{bp.QTREE_ENTITY}/nodes',
            rr.Points2D([xy[n] for n in order], labels=labels,
                        colors=[node_color(n) for n in order],
                        radii=[9.0 if n in on_path else 5.0 for n in order], show_labels=True),
        )  # fmt: skip
        self.rec.log(
            f'{bp.QTREE_ENTITY}/edges',
            rr.LineStrips2D([[xy[e.parent], xy[e.child]] for e in drawing.edges],
                            colors=[HIGHLIGHT_COLOR if e.highlighted else EDGE_COLORS[e.kind]
                                    for e in drawing.edges],
                            radii=[3.0 if e.highlighted else 1.0 for e in drawing.edges]),
        )  # fmt: skip
        note = (f'top {QTREE_TOP_K} per level by Q: {len(order)} of {drawing.total_nodes} nodes'
                if drawing.omitted_nodes else f'all {drawing.total_nodes} nodes')  # fmt: skip
        self.rec.log(
            f'{bp.QTREE_ENTITY}/note',
            rr.Points2D([xy[0] - [0.0, QTREE_Y_SPACING * 0.8]] if order else [[0.0, 0.0]],
                        labels=[note], radii=[0.5], show_labels=True),
        )  # fmt: skip

    @_guarded
    def on_training_stats(
        self,
        episode: int,
        q_bar: float,
        nodes: int,
        edges: int,
        mp_calls: int,
        epsilon: float,
        t_ns: int | None = None,
    ) -> None:
        """Append one episode to the curves (``episode`` timeline, and log time when given).

        Args:
            episode: episode index.
            q_bar: Q̄, sum of |Q| over the edges (eq. 10).
            nodes: tree nodes.
            edges: tree edges.
            mp_calls: motion-planner calls as the paper counts them.
            epsilon: exploration rate ε.
            t_ns: time [ns since epoch], if known.
        """
        self._set_time(t_ns, episode)
        values = {'q_bar': q_bar, 'nodes': nodes, 'edges': edges, 'mp_calls': mp_calls,
                  'epsilon': epsilon}  # fmt: skip
        for name, value in values.items():
            self.rec.log(f'{bp.STATS_ENTITY}/{name}', rr.Scalars(float(value)))

    @_guarded
    def on_tracking(
        self,
        object_id: str,
        phase: str,
        reference: Sequence[float],
        actual: Sequence[float],
        error_m: float,
        t_ns: int,
        message: str = '',
    ) -> None:
        """One closed-loop tick: EE reference vs actual path of ``object_id``, error curve.

        Args:
            object_id: the object being relocated.
            phase: ``'tracking'``, ``'settling'``, ``'done'`` or ``'stopped'``.
            reference: reference EE position [m] (3,).
            actual: EE position at the measured joints [m] (3,).
            error_m: EE position error [m].
            t_ns: time [ns since epoch].
            message: why the execution stopped (``'stopped'``).
        """
        self._set_time(t_ns)
        if phase == 'stopped':
            self.rec.log(EVENTS_STOP, rr.TextLog(message or 'stopped', level='WARN'))
            return
        track = self._track
        if track['id'][0] != object_id:
            track['id'][0], track['reference'], track['actual'], track['chunk'] = (
                object_id,
                [],
                [],
                [0],
            )
        track['reference'].append(np.asarray(reference, dtype=float)[:3])
        track['actual'].append(np.asarray(actual, dtype=float)[:3])
        self.rec.log(f'{bp.TRACKING_ENTITY}/error_mm', rr.Scalars(float(error_m) * 1e3))
        if len(track['actual']) < TRACK_EVERY and phase != 'done':
            return
        # Each piece of path is logged once, to its own entity (the data grows linearly).
        chunk = track['chunk'][0]
        for name in ('reference', 'actual'):
            self.rec.log(
                f'{bp.TRACKING_ENTITY}/{object_id}/{name}/{chunk:04d}',
                rr.LineStrips3D([np.array(track[name])], colors=[TRACK_COLORS[name]],
                                radii=[0.003]),
                rr.CoordinateFrame(bp.WORLD_FRAME),
            )  # fmt: skip
            track[name] = track[name][-1:]  # the next piece starts where this one ends
        track['chunk'][0] = chunk + 1

    @_guarded
    def on_message(self, topic: str, msg: Any, t_ns: int) -> bool:
        """Log a decoded message of one of :data:`TOPICS`; other topics are ignored.

        Args:
            topic: topic name.
            msg: the decoded message (fields as attributes).
            t_ns: log time [ns since epoch].

        Returns:
            True when the topic is one the view shows.
        """
        self._log_world(topic, msg, t_ns)
        if topic == REPLAN_TOPIC:
            pass  # shown by _log_world only
        elif topic == '/joint_states':
            self.on_joint_state(list(msg.name), [float(v) for v in msg.position], t_ns)
        elif topic == '/scene':
            zone = msg.drop_zone.position, msg.drop_zone_size
            self.on_scene(
                scene_objects(msg), t_ns,
                drop_zone=((zone[0].x, zone[0].y, zone[0].z), (zone[1].x, zone[1].y, zone[1].z)),
            )  # fmt: skip
        elif topic == '/motion_planner/events':
            reason = REASONS.get(int(msg.reason), str(msg.reason))
            self.on_planning_event(
                msg.object_id, list(msg.relocated_ids), bool(msg.feasible), reason, t_ns,
                planning_time_s=float(msg.planning_time), from_cache=bool(msg.from_cache),
                execute=bool(msg.execute), message=str(msg.message),
            )  # fmt: skip
            self.on_ee_path(msg.object_id, pose_array(msg.ee_path), bool(msg.feasible), t_ns)
        elif topic == '/qtree':
            edges = [(int(e.parent), int(e.child), str(e.object_id), float(e.q),
                      bool(e.on_best_path), float(e.reward)) for e in msg.edges]  # fmt: skip
            self.on_qtree(list(msg.node_sequences), edges, int(msg.episode), t_ns)
        elif topic == '/training_stats':
            self.on_training_stats(
                int(msg.episode),
                float(msg.q_bar),
                int(msg.nodes),
                int(msg.edges),
                int(msg.mp_calls),
                float(msg.epsilon),
                t_ns,
            )
        elif topic == '/motion_planner/tracking':
            ref, act = msg.ee_reference.position, msg.ee_measured.position
            self.on_tracking(
                str(msg.object_id), str(msg.phase), (ref.x, ref.y, ref.z), (act.x, act.y, act.z),
                float(msg.error_m), t_ns, str(msg.message),
            )  # fmt: skip
        elif topic == '/robot_description':
            if self._urdf is None:
                self._tmpdir = tempfile.TemporaryDirectory(prefix='qtree_urdf_')
                path = Path(self._tmpdir.name) / 'robot_description.urdf'
                path.write_text(str(msg.data), encoding='utf-8')
                self.on_robot_description(path)
        else:
            return False
        return True

    def _log_world(self, topic: str, msg: Any, t_ns: int) -> None:
        """Scene events and re-plans (:mod:`.world_changes`) as warnings on ``/events/world``."""
        lines = self._world.on_message(topic, msg)
        if lines:
            self._set_time(t_ns)
        for line in lines:
            level = rr.TextLogLevel.INFO if ' planned:' in line else rr.TextLogLevel.WARN
            self.rec.log(WORLD_ENTITY, rr.TextLog(line, level=level))

    def flush(self) -> None:
        """Flush pending data to the sink (never raises)."""
        try:
            self.rec.flush()
        except Exception as err:
            _LOG.warning('Rerun view: flush failed (%s)', err)

    def close(self) -> None:
        """Flush and close the recording (never raises; idempotent)."""
        try:
            self.rec.flush()
            self.rec.disconnect()
        except Exception as err:
            _LOG.warning('Rerun view: close failed (%s)', err)
        if self._tmpdir is not None:
            self._tmpdir.cleanup()
            self._tmpdir = None


def scene_objects(msg: Any) -> list[dict[str, Any]]:
    """Convert a ``qtree_msgs/msg/Scene`` (decoded, attribute access) to scene-object dicts."""
    objects = []
    for obj in msg.objects:
        p, q = obj.pose.position, obj.pose.orientation
        shape, radius, height, size = object_geometry(obj)
        objects.append({
            'id': str(obj.id),
            'role': ROLES.get(int(obj.role), 'obstacle'),
            'shape': shape,
            'status': STATUSES.get(int(obj.status), 'in_clutter'),
            'radius': radius,
            'height': height,
            'size': size,
            'position': (float(p.x), float(p.y), float(p.z)),
            'orientation': (float(q.x), float(q.y), float(q.z), float(q.w)),
        })  # fmt: skip
    return objects


def pose_array(msg: Any) -> np.ndarray:
    """Convert a ``geometry_msgs/msg/PoseArray`` to an array, shape (M, 7): x, y, z, qx..qw."""
    rows = [(p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y,
             p.orientation.z, p.orientation.w) for p in msg.poses]  # fmt: skip
    return np.asarray(rows, dtype=float).reshape(-1, 7)


def _object_archetypes(obj: dict[str, Any]) -> list[Any]:
    """Rerun archetypes of one scene object (shape, colour by role/status, world frame)."""
    role, status = str(obj.get('role', 'obstacle')), str(obj.get('status', 'in_clutter'))
    color = ROLE_COLORS.get(role, ROLE_COLORS['obstacle'])
    if status == 'relocated':
        color = RELOCATED_COLOR
    elif status == 'grasped':
        color = GRASPED_COLOR
    centre = [float(v) for v in obj['position']]
    quaternion = rr.Quaternion(xyzw=[float(v) for v in obj.get('orientation', (0, 0, 0, 1))])
    label = str(obj['id']) if role != 'static' else None
    shape: rr.Boxes3D | rr.Cylinders3D
    if obj.get('shape', 'cylinder') == 'box':
        shape = rr.Boxes3D(centers=[centre], sizes=[[float(v) for v in obj['size']]],
                           quaternions=[quaternion], colors=[color], fill_mode='solid',
                           labels=label)  # fmt: skip
    else:
        shape = rr.Cylinders3D(centers=[centre], lengths=[float(obj['height'])],
                               radii=[float(obj['radius'])], quaternions=[quaternion],
                               colors=[color], fill_mode='solid', labels=label)  # fmt: skip
    return [shape, rr.CoordinateFrame(bp.WORLD_FRAME)]
