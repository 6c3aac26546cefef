"""Scene markers and object frames (qtree_recorder.markers)."""

from __future__ import annotations

from types import SimpleNamespace as Msg

import pytest
from mcap_ros2._dynamic import generate_dynamic
from qtree_recorder.definitions import DefinitionLibrary
from qtree_recorder.encoding import DynamicEncoder
from qtree_recorder.markers import (
    COLOR_GRASPED,
    COLOR_OBSTACLE,
    COLOR_RELOCATED,
    COLOR_STATIC,
    COLOR_TARGET,
    object_color,
    object_geometry,
    object_scale,
    object_transforms,
    scene_markers,
)

MARKER_ARRAY = 'visualization_msgs/msg/MarkerArray'


def vec(x: float, y: float, z: float) -> Msg:
    return Msg(x=x, y=y, z=z)


def pose(x: float, y: float, z: float, qw: float = 1.0) -> Msg:
    return Msg(position=vec(x, y, z), orientation=Msg(x=0.0, y=0.0, z=0.0, w=qw))


def obj(id_: str, role: int, shape: int, status: int = 0, **kw) -> Msg:
    """An ObjectState; ``shape`` 0 cylinder (radius, height), 1 box (box), as SolidPrimitive."""
    if shape == 0:
        primitive = Msg(type=3, dimensions=[kw.get('height', 0.0), kw.get('radius', 0.0)])
    else:
        box = kw.get('box', vec(0, 0, 0))
        primitive = Msg(type=1, dimensions=[box.x, box.y, box.z])
    return Msg(id=id_, role=role, shape=primitive, status=status,
               pose=kw.get('pose', pose(0.5, 0.0, 0.06)))  # fmt: skip


@pytest.fixture
def scene() -> Msg:
    objects = [
        obj('T', 0, 0, radius=0.03, height=0.12, pose=pose(0.55, 0.05, 0.06)),
        obj('O1', 1, 0, radius=0.035, height=0.14),
        obj('O2', 1, 0, status=2, radius=0.035, height=0.14),
        obj('O3', 1, 0, status=1, radius=0.035, height=0.14, pose=pose(0.3, 0.2, 0.4, qw=0.0)),
        obj('table', 2, 1, box=vec(0.8, 1.2, 0.04), pose=pose(0.6, 0.0, -0.02)),
    ]
    return Msg(objects=objects, attached_id='O3', drop_zone=pose(0.0, 0.6, 0.0),
               drop_zone_size=vec(0.3, 0.3, 0.01))  # fmt: skip


def test_colours_by_role_and_status() -> None:
    assert object_color(0, 0) == COLOR_TARGET
    assert object_color(1, 0) == COLOR_OBSTACLE
    assert object_color(1, 2) == COLOR_RELOCATED
    assert object_color(2, 0) == COLOR_STATIC
    assert object_color(1, 1) == COLOR_GRASPED
    assert object_color(0, 0, attached=True) == COLOR_GRASPED


def test_markers_encode_and_decode(scene: Msg) -> None:
    array = scene_markers(scene, 1_700_000_000_000_000_005)
    cdr = DynamicEncoder().encode(MARKER_ARRAY, array)
    text = DefinitionLibrary().definition(MARKER_ARRAY).text
    markers = generate_dynamic(MARKER_ARRAY, text)[MARKER_ARRAY](cdr).markers
    assert markers[0].action == 3  # DELETEALL first
    shapes = [m for m in markers if m.ns == 'objects']
    labels = [m for m in markers if m.ns == 'labels']
    assert [m.type for m in shapes] == [3, 3, 3, 3, 1]  # cylinders, then the table box
    assert [m.text for m in labels] == ['T', 'O1', 'O2', 'O3']  # no label on the table
    target = shapes[0]
    assert (target.scale.x, target.scale.y, target.scale.z) == pytest.approx((0.06, 0.06, 0.12))
    assert (target.color.r, target.color.g, target.color.b) == pytest.approx(COLOR_TARGET[:3])
    assert target.pose.position.x == pytest.approx(0.55) and target.header.frame_id == 'world'
    assert target.header.stamp.nanosec == 5
    assert (shapes[2].color.r, shapes[2].color.g) == pytest.approx(COLOR_RELOCATED[:2])
    assert shapes[3].color.g == pytest.approx(COLOR_GRASPED[1])
    assert shapes[3].pose.orientation.w == 1.0  # an unset quaternion becomes identity
    table = shapes[4]
    assert (table.scale.x, table.scale.y, table.scale.z) == pytest.approx((0.8, 1.2, 0.04))
    assert labels[0].pose.position.z == pytest.approx(0.06 + 0.06 + 0.04)
    zone = [m for m in markers if m.ns == 'drop_zone']
    assert len(zone) == 1 and zone[0].color.a == pytest.approx(0.25)


def test_object_frames(scene: Msg) -> None:
    frames = object_transforms(scene)
    assert [f.child for f in frames] == ['object/T', 'object/O1', 'object/O2', 'object/O3',
                                         'object/table']  # fmt: skip
    assert all(f.parent == 'world' for f in frames)
    assert frames[0].translation == pytest.approx((0.55, 0.05, 0.06))
    assert frames[3].rotation == (0.0, 0.0, 0.0, 1.0)


def test_bad_scene_is_reported() -> None:
    with pytest.raises(AttributeError):
        scene_markers(Msg(objects=[Msg(id='x')]), 0)


def test_solid_primitive_and_legacy_shapes() -> None:
    cylinder = obj('T', 0, 0, radius=0.03, height=0.12)
    assert object_geometry(cylinder) == ('cylinder', 0.03, 0.12, (0.0, 0.0, 0.0))
    box = obj('B', 1, 1, box=vec(0.1, 0.2, 0.3))
    assert object_geometry(box) == ('box', 0.0, 0.0, (0.1, 0.2, 0.3))
    # Logs recorded before SolidPrimitive shapes: shape code + radius/height/box_size fields.
    legacy = Msg(shape=0, radius=0.04, height=0.2, box_size=vec(0, 0, 0))
    assert object_geometry(legacy) == ('cylinder', 0.04, 0.2, (0.0, 0.0, 0.0))
    legacy_box = Msg(shape=1, radius=0.0, height=0.0, box_size=vec(0.7, 1.0, 0.04))
    assert object_scale(legacy_box) == {'x': 0.7, 'y': 1.0, 'z': 0.04}
    assert object_scale(cylinder) == {'x': 0.06, 'y': 0.06, 'z': 0.12}
