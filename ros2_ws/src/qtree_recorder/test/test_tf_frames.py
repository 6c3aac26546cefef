"""Arm /tf from joint states (qtree_recorder.tf_frames) against jaco2_description's model."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from jaco2_description import model as jaco2_model
from mcap_ros2._dynamic import generate_dynamic
from qtree_recorder.definitions import DefinitionLibrary
from qtree_recorder.encoding import DynamicEncoder
from qtree_recorder.exceptions import RobotModelError
from qtree_recorder.tf_frames import ArmFrames, FrameTransform, tf_message

ARM = [f'j2s7s300_joint_{i}' for i in range(1, 8)]


@pytest.fixture(scope='module')
def frames() -> ArmFrames:
    return ArmFrames(jaco2_model.urdf_text())


def se3(t: FrameTransform) -> pin.SE3:
    x, y, z, w = t.rotation
    return pin.SE3(pin.Quaternion(w, x, y, z).toRotationMatrix(), np.array(t.translation))


def chain_to_root(transforms: dict[str, FrameTransform], link: str) -> pin.SE3:
    placement = pin.SE3.Identity()
    while link in transforms:
        placement = se3(transforms[link]) * placement
        link = transforms[link].parent
    return placement


def test_frames_cover_every_link(frames: ArmFrames) -> None:
    assert frames.root_link == 'j2s7s300_link_base'
    assert frames.static_children == ('j2s7s300_end_effector',)
    assert len(frames.moving_children) == 13  # 7 arm links + 3 fingers + 3 finger tips
    assert set(ARM) <= set(frames.joint_names)


def test_matches_jaco2_description_link_placements(frames: ArmFrames) -> None:
    rng = np.random.default_rng(3)
    names = list(frames.joint_names)
    for _ in range(5):
        q = rng.uniform(0.9, 5.0, len(names))
        reference = jaco2_model.link_placements(dict(zip(names, q, strict=True)))
        for t in frames.moving_transforms(names, q):
            expected = reference[t.child]
            assert np.allclose(se3(t).homogeneous, expected.homogeneous, atol=1e-9), t.child
            assert t.parent == jaco2_model.link_parents()[t.child]


def test_candle_pose_puts_the_end_effector_at_1_2603_m(frames: ArmFrames) -> None:
    moving = frames.moving_transforms(ARM, [math.pi] * 7)
    tree = {t.child: t for t in moving + frames.static_transforms()}
    ee = chain_to_root(tree, 'j2s7s300_end_effector')
    assert ee.translation == pytest.approx([0.0, -0.013, 1.2603], abs=1e-3)  # KINOVA_FACTS.md
    assert tree['j2s7s300_link_base'].parent == 'world'
    assert tree['j2s7s300_link_base'].rotation == (0.0, 0.0, 0.0, 1.0)


def test_continuous_joint_wraps(frames: ArmFrames) -> None:
    a = frames.moving_transforms(['j2s7s300_joint_1'], [0.3])[0]
    b = frames.moving_transforms(['j2s7s300_joint_1'], [0.3 + 2 * math.pi])[0]
    assert np.allclose(se3(a).homogeneous, se3(b).homogeneous, atol=1e-12)


def test_bad_inputs(frames: ArmFrames) -> None:
    with pytest.raises(RobotModelError, match='2 joint names but 1 positions'):
        frames.moving_transforms(ARM[:2], [0.0])
    with pytest.raises(RobotModelError, match='not finite'):
        frames.moving_transforms(ARM[:1], [math.nan])
    unknown = frames.moving_transforms(['other_robot_joint'], [1.0])  # ignored, not an error
    assert len(unknown) == 13
    for text in ('<robot name="r"><link name="a"/>', 'not xml at all', '<robot name="r"/>'):
        with pytest.raises(RobotModelError, match='cannot build the /tf model'):
            ArmFrames(text)


def test_tf_message_encodes_and_decodes(frames: ArmFrames) -> None:
    transforms = frames.moving_transforms(ARM, [math.pi] * 7)
    stamp_ns = 1_700_000_000_123_456_789
    cdr = DynamicEncoder().encode('tf2_msgs/msg/TFMessage', tf_message(transforms, stamp_ns))
    text = DefinitionLibrary().definition('tf2_msgs/msg/TFMessage').text
    decoded = generate_dynamic('tf2_msgs/msg/TFMessage', text)['tf2_msgs/msg/TFMessage'](cdr)
    assert len(decoded.transforms) == 13
    first = decoded.transforms[0]
    assert (first.header.stamp.sec, first.header.stamp.nanosec) == (1_700_000_000, 123_456_789)
    assert first.header.frame_id == 'j2s7s300_link_base'
    assert first.child_frame_id == 'j2s7s300_link_1'
    assert first.transform.translation.z == pytest.approx(0.15675)
