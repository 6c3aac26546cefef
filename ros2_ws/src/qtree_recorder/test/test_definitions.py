"""Full ros2msg definitions assembled as rosbag2 does (qtree_recorder.definitions)."""

from __future__ import annotations

from pathlib import Path

import pytest
from ament_index_python.packages import get_package_share_directory
from qtree_recorder.definitions import (
    SEPARATOR,
    DefinitionLibrary,
    parse_dependencies,
    split_type_name,
)
from qtree_recorder.exceptions import InvalidTypeNameError
from rosbags.typesys import get_types_from_msg


def blocks(text: str) -> list[str]:
    """Names of the dependency blocks, in order."""
    return [line[5:] for line in text.splitlines() if line.startswith('MSG: ')]


@pytest.fixture
def library() -> DefinitionLibrary:
    return DefinitionLibrary()


def test_joint_state_is_complete_down_to_time(library: DefinitionLibrary) -> None:
    definition = library.definition('sensor_msgs/msg/JointState')
    own = (Path(get_package_share_directory('sensor_msgs')) / 'msg/JointState.msg').read_text()
    assert definition.complete
    assert definition.text.startswith(own)
    assert blocks(definition.text) == ['std_msgs/Header', 'builtin_interfaces/Time']
    assert definition.text.count(SEPARATOR + '\n') == 2
    assert f'\n{SEPARATOR}\nMSG: builtin_interfaces/Time\n' in definition.text
    assert 'uint32 nanosec' in definition.text
    assert len(SEPARATOR) == 80 and set(SEPARATOR) == {'='}


def test_scene_has_every_dependency_once_in_rosbag2_order(library: DefinitionLibrary) -> None:
    definition = library.definition('qtree_msgs/msg/Scene')
    # rosbag2: dependencies sorted, depth first, each once.
    assert blocks(definition.text) == [
        'geometry_msgs/Pose',
        'geometry_msgs/Point',
        'geometry_msgs/Quaternion',
        'geometry_msgs/Vector3',
        'qtree_msgs/ObjectState',
        'shape_msgs/SolidPrimitive',
        'geometry_msgs/Polygon',
        'geometry_msgs/Point32',
        'std_msgs/Header',
        'builtin_interfaces/Time',
    ]
    assert definition.missing == ()
    assert definition.text.startswith('# The world the arm plans against')
    # ObjectState's constants survive in its block.
    assert 'uint8 STATUS_RELOCATED=2' in definition.text


def test_rosbags_parses_every_block(library: DefinitionLibrary) -> None:
    types = get_types_from_msg(library.definition('qtree_msgs/msg/Scene').text,
                               'qtree_msgs/msg/Scene')  # fmt: skip
    assert {'qtree_msgs/msg/Scene', 'qtree_msgs/msg/ObjectState', 'builtin_interfaces/msg/Time',
            'geometry_msgs/msg/Pose', 'shape_msgs/msg/SolidPrimitive'} <= set(types)  # fmt: skip


def test_bundled_tf_message_and_action_feedback(library: DefinitionLibrary) -> None:
    tf = library.definition('tf2_msgs/msg/TFMessage')
    assert tf.text.startswith('geometry_msgs/TransformStamped[] transforms\n')
    assert blocks(tf.text)[-1] == 'builtin_interfaces/Time' and tf.complete
    feedback = library.definition('qtree_msgs/action/RetrieveTarget_FeedbackMessage')
    assert feedback.text.startswith(
        'unique_identifier_msgs/UUID goal_id\nqtree_msgs/action/RetrieveTarget_Feedback feedback\n'
    )
    assert blocks(feedback.text) == [
        'qtree_msgs/action/RetrieveTarget_Feedback',
        'unique_identifier_msgs/UUID',
    ]
    assert 'string[] best_sequence' in feedback.text and 'uint8[16] uuid' in feedback.text
    goal = library.definition('qtree_msgs/action/RetrieveTarget_Goal').text
    assert 'string policy "H-EG"' in goal and 'best_sequence' not in goal
    status = library.definition('action_msgs/msg/GoalStatusArray')
    assert blocks(status.text) == [
        'action_msgs/GoalStatus', 'action_msgs/GoalInfo', 'builtin_interfaces/Time',
        'unique_identifier_msgs/UUID',
    ]  # fmt: skip


def test_parse_dependencies_handles_msg_syntax() -> None:
    text = (
        '# comment with geometry_msgs/Pose inside\n'
        'uint8 ROLE_A=0\n'
        'int8 STATUS_X   = 3\n'
        'Header header\n'
        'string<=10 short_name\n'
        'string policy "H-EG"\n'
        'float64[3] xyz [1.0, 2.0, 3.0]\n'
        'Local[] locals\n'
        'geometry_msgs/Point[<=4] points\n'
        'builtin_interfaces/Time stamp\n'
    )
    assert parse_dependencies(text, 'pkg') == [
        'builtin_interfaces/Time',
        'geometry_msgs/Point',
        'pkg/Local',
        'std_msgs/Header',
    ]


def test_missing_dependency_warns_once_and_keeps_the_rest(tmp_path: Path) -> None:
    share = tmp_path / 'share'
    (share / 'mine' / 'msg').mkdir(parents=True)
    (share / 'mine' / 'msg' / 'Thing.msg').write_text('int32 a\nnope_msgs/Gone g\nPart p\n')
    (share / 'mine' / 'msg' / 'Part.msg').write_text('float64 x\n')
    warnings: list[str] = []

    def lookup(package: str) -> str:
        if package != 'mine':
            raise KeyError(package)
        return str(share / package)

    library = DefinitionLibrary(share_lookup=lookup, warn=warnings.append)
    definition = library.definition('mine/msg/Thing')
    assert definition.missing == ('nope_msgs/Gone',)
    assert blocks(definition.text) == ['mine/Part']
    assert definition.text.startswith('int32 a\n')
    library.definition('mine/msg/Thing')
    assert len(warnings) == 1 and 'mine/msg/Thing' in warnings[0]
    assert 'nope_msgs/Gone' in warnings[0]


def test_unknown_top_level_type_gives_empty_text_and_one_warning() -> None:
    warnings: list[str] = []
    library = DefinitionLibrary(warn=warnings.append)
    definition = library.definition('no_such_pkg/msg/Thing')
    assert definition.text == '' and definition.missing == ('no_such_pkg/msg/Thing',)
    library.definition('no_such_pkg/msg/Thing')
    assert len(warnings) == 1 and 'no_such_pkg/msg/Thing' in warnings[0]


def test_split_type_name() -> None:
    assert split_type_name('std_msgs/Header') == ('std_msgs', 'msg', 'Header')
    assert split_type_name('a/action/B_Goal') == ('a', 'action', 'B_Goal')
    for bad in ('Header', 'a/b/c/d', '', 'pkg/9Type'):
        with pytest.raises(InvalidTypeNameError, match='invalid ROS type name'):
            split_type_name(bad)


def test_type_hash_from_the_installed_json(library: DefinitionLibrary) -> None:
    joint_state = library.type_hash('sensor_msgs/msg/JointState')
    assert joint_state.startswith('RIHS01_') and len(joint_state) == 7 + 64
    assert library.type_hash('qtree_msgs/msg/Scene').startswith('RIHS01_')
    assert library.type_hash('tf2_msgs/msg/TFMessage') == ''  # bundled text, no JSON
    assert library.type_hash('no_such_pkg/msg/X') == ''


def test_tracking_state_is_complete(library: DefinitionLibrary) -> None:
    definition = library.definition('qtree_msgs/msg/TrackingState')
    assert definition.complete and definition.missing == ()
    assert blocks(definition.text) == [
        'geometry_msgs/Pose',
        'geometry_msgs/Point',
        'geometry_msgs/Quaternion',
        'std_msgs/Header',
        'builtin_interfaces/Time',
    ]
    types = get_types_from_msg(definition.text, 'qtree_msgs/msg/TrackingState')
    assert 'qtree_msgs/msg/TrackingState' in types
