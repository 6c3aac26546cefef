"""Default Rerun layout of a qtree-tamp run (live view and converted logs alike). No rclpy.

Left: the 3D scene (arm from its URDF, table, objects, planned end-effector paths) in the robot
base frame. Right: the Q-tree graph on top, the episode curves (Q̄; nodes, edges and MP calls;
ε) and the closed-loop EE tracking error as tabs below it, and the planning-event log at the
bottom.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

WORLD_FRAME = 'j2s7s300_link_base'  # world = robot base frame, z up
ROBOT_ENTITY = '/j2s7s300'  # root entity of Rerun's URDF loader (the robot's name)
SCENE_ENTITY = '/scene'
PLANS_ENTITY = '/plans'
QTREE_ENTITY = '/qtree'
STATS_ENTITY = '/stats'
EVENTS_ENTITY = '/events'
TRACKING_ENTITY = '/tracking'  # closed-loop execution: EE reference vs actual path, error curve
TIME_TIMELINE = 'ros_time'  # log time of each message (timestamp)
EPISODE_TIMELINE = 'episode'  # training episode (sequence)
LEVEL_SPACING = 80.0  # Q-tree layout: distance between levels [graph units]
SIBLING_SPACING = 120.0  # Q-tree layout: distance between neighbouring leaves [graph units]


def default_blueprint(*, robot_entity: str = ROBOT_ENTITY) -> rrb.Blueprint:
    """The default layout.

    Args:
        robot_entity: root entity of the logged URDF (its collision geometry is left out).

    Returns:
        A blueprint to pass to ``RecordingStream.save``/``spawn``.
    """
    scene_view = rrb.Spatial3DView(
        name='Jaco² and scene',
        origin='/',
        contents=[
            f'+ {robot_entity}/**',
            f'- {robot_entity}/collision_geometries/**',
            f'+ {SCENE_ENTITY}/**',
            f'+ {PLANS_ENTITY}/**',
            f'+ {TRACKING_ENTITY}/**',
            f'- {TRACKING_ENTITY}/error_mm',
        ],
        spatial_information=rrb.archetypes.SpatialInformation(
            target_frame=WORLD_FRAME, show_axes=True
        ),
        eye_controls=rrb.archetypes.EyeControls3D(
            position=(1.25, -1.05, 0.85), look_target=(0.35, 0.05, 0.15), eye_up=(0.0, 0.0, 1.0)
        ),
        # The URDF loader logs primitives without a fill mode: draw them solid, not as wireframes.
        defaults=[
            rr.Boxes3D.from_fields(fill_mode='solid'),
            rr.Cylinders3D.from_fields(fill_mode='solid'),
        ],
    )
    curves = rrb.Tabs(
        rrb.TimeSeriesView(name='Q̄ (eq. 10)', origin=f'{STATS_ENTITY}/q_bar'),
        rrb.TimeSeriesView(
            name='nodes, edges, MP calls',
            origin=STATS_ENTITY,
            contents=[
                f'{STATS_ENTITY}/nodes',
                f'{STATS_ENTITY}/edges',
                f'{STATS_ENTITY}/mp_calls',
            ],
        ),
        rrb.TimeSeriesView(name='ε', origin=f'{STATS_ENTITY}/epsilon'),
        rrb.TimeSeriesView(name='EE tracking error [mm]', origin=f'{TRACKING_ENTITY}/error_mm'),
        name='episode curves',
    )
    right = rrb.Vertical(
        rrb.Spatial2DView(
            name='Q-tree (top 4 per level by Q, extracted path orange)', origin=QTREE_ENTITY
        ),
        curves,
        rrb.TextLogView(
            name='planning events',
            origin=EVENTS_ENTITY,
            columns=rrb.archetypes.TextLogColumns(
                timeline_columns=[rrb.components.TimelineColumn(EPISODE_TIMELINE, visible=False)],
                text_log_columns=[
                    rrb.components.TextLogColumn('LogLevel'),
                    rrb.components.TextLogColumn('Body'),
                    rrb.components.TextLogColumn('EntityPath', visible=False),
                ],
            ),
        ),
        row_shares=[3, 2, 2],
    )
    return rrb.Blueprint(
        rrb.Horizontal(scene_view, right, column_shares=[1, 1]),
        rrb.TimePanel(timeline=TIME_TIMELINE, expanded=False, play_state='following'),
        collapse_panels=True,
    )


def log_series_styles(recording: rr.RecordingStream) -> None:
    """Name and colour the episode curves (static, once per recording)."""
    styles = {
        'q_bar': ('Q̄', (31, 119, 180)),
        'nodes': ('nodes', (44, 160, 44)),
        'edges': ('edges', (148, 103, 189)),
        'mp_calls': ('MP calls', (214, 39, 40)),
        'epsilon': ('ε', (255, 127, 14)),
    }
    for name, (label, color) in styles.items():
        recording.log(
            f'{STATS_ENTITY}/{name}',
            rr.SeriesLines(names=label, colors=[color], widths=2.0),
            static=True,
        )


def tree_layout(count: int, edges: Sequence[tuple[int, int]]) -> np.ndarray:
    """Tidy top-down positions of a tree: depth gives y, leaves spread evenly along x.

    Args:
        count: number of nodes (node 0 is the root).
        edges: ``(parent, child)`` pairs.

    Returns:
        Positions, shape (count, 2) [graph units].
    """
    children: dict[int, list[int]] = {}
    for parent, child in edges:
        children.setdefault(parent, []).append(child)
    positions = np.zeros((count, 2))
    next_leaf = 0.0
    stack: list[tuple[int, int, bool]] = [(0, 0, False)] if count else []
    seen: set[int] = set()
    while stack:
        node, depth, expanded = stack.pop()
        kids = [k for k in children.get(node, []) if 0 <= k < count and k not in seen]
        if not expanded and kids:
            seen.update(kids)
            stack.append((node, depth, True))
            stack.extend((k, depth + 1, False) for k in reversed(kids))
            continue
        placed = [k for k in children.get(node, []) if 0 <= k < count]
        if expanded and placed:
            x = float(np.mean(positions[placed, 0]))
        else:
            x, next_leaf = next_leaf, next_leaf + SIBLING_SPACING
        positions[node] = (x, depth * LEVEL_SPACING)
    return positions
