"""Complete ``ros2msg`` definition texts, assembled the way rosbag2 (Jazzy) writes MCAP schemas.

rosbag2's ``LocalMessageDefinitionSource`` reads ``<share>/<pkg>/msg/<Type>.msg`` through the
ament index, then appends every dependency once, depth first, in sorted order, each after a blank
line, a line of 80 ``=`` and ``MSG: <name as referenced>``::

    std_msgs/Header header
    string[] name
    ...
    ================================================================================
    MSG: std_msgs/Header
    builtin_interfaces/Time stamp
    string frame_id
    ================================================================================
    MSG: builtin_interfaces/Time
    int32 sec
    uint32 nanosec

Readers (rosbags, Foxglove, Rerun) need every block down to ``builtin_interfaces/Time``: Rerun
keeps a channel as raw bytes when one is missing. No ROS import here, only ``ament_index_python``.

Two additions over rosbag2 Jazzy, which cannot define these:

* ``tf2_msgs/msg/TFMessage`` ships with this package (``BUNDLED_DEFINITIONS``) because there is no
  tf2_msgs wheel; its definition is one line, ``geometry_msgs/TransformStamped[] transforms``.
* Action messages (``pkg/action/X_Goal|_Result|_Feedback`` from ``X.action``, and the hidden
  feedback topic's ``pkg/action/X_FeedbackMessage`` = ``unique_identifier_msgs/UUID goal_id`` +
  ``X_Feedback feedback``) and service parts (``pkg/srv/X_Request|_Response``).
"""

from __future__ import annotations

import json
import logging
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from qtree_recorder.exceptions import DefinitionNotFoundError, InvalidTypeNameError

SEPARATOR = '=' * 80

# Definitions shipped with this package for types without an installed interface package.
# tf2_msgs has no PyPI wheel; this is the text of tf2_msgs/msg/TFMessage.msg (ROS 2 Jazzy).
BUNDLED_DEFINITIONS: dict[str, str] = {
    'tf2_msgs/msg/TFMessage': 'geometry_msgs/TransformStamped[] transforms\n',
}

PRIMITIVE_TYPES = frozenset(
    {
        'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8', 'int16', 'uint16',
        'int32', 'uint32', 'int64', 'uint64', 'string', 'wstring',
    }
)  # fmt: skip

# rosbag2's MSG_FIELD_TYPE_REGEX: the type at the start of a line, an optional array suffix.
_FIELD_TYPE = re.compile(r'(?:^|\n)\s*([a-zA-Z0-9_/]+)(?:\[[^\]]*\])?\s+')
_NAME = r'[a-zA-Z][a-zA-Z0-9_]*'
_TYPE_NAME = re.compile(rf'^({_NAME})/(?:({_NAME})/)?({_NAME})$')
_SECTION_SEPARATOR = re.compile(r'^---[ \t]*$', re.MULTILINE)
_ACTION_PARTS = {'_Goal': 0, '_Result': 1, '_Feedback': 2}
_SERVICE_PARTS = {'_Request': 0, '_Response': 1}

ShareLookup = Callable[[str], str]


def split_type_name(type_name: str) -> tuple[str, str, str]:
    """Split ``pkg/Type`` or ``pkg/ns/Type`` into ``(pkg, ns, Type)``; ``ns`` defaults to msg.

    Raises:
        InvalidTypeNameError: the name has another form.
    """
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise InvalidTypeNameError(type_name)
    package, namespace, name = match.groups()
    return package, namespace or 'msg', name


def parse_dependencies(text: str, package: str) -> list[str]:
    """Names of the non-primitive field types of a ``.msg`` text, sorted, as referenced.

    Short names get the package context (``Foo`` in pkg → ``pkg/Foo``); ``Header`` is
    ``std_msgs/Header``. Constants (``uint8 A=1``), defaults, bounded strings and comments are
    handled by the field-type pattern rosbag2 uses.

    Args:
        text: the ``.msg`` file content.
        package: the package the text belongs to.
    """
    dependencies: set[str] = set()
    for match in _FIELD_TYPE.finditer(text):
        field_type = match.group(1)
        if field_type in PRIMITIVE_TYPES:
            continue
        if field_type == 'Header':
            dependencies.add('std_msgs/Header')
        elif '/' not in field_type:
            dependencies.add(f'{package}/{field_type}')
        else:
            dependencies.add(field_type)
    return sorted(dependencies)


def _default_share_lookup(package: str) -> str:
    from ament_index_python.packages import get_package_share_directory

    return get_package_share_directory(package)


@dataclass(frozen=True)
class Definition:
    """A full definition text and the types that could not be resolved in it.

    Attributes:
        type_name: the top-level type, e.g. ``'sensor_msgs/msg/JointState'``.
        text: the complete ``ros2msg`` text (top level first, then every dependency block).
        missing: types whose ``.msg`` was not found (empty when the text is complete).
    """

    type_name: str
    text: str
    missing: tuple[str, ...] = ()

    @property
    def complete(self) -> bool:
        """True when every dependency block is present."""
        return not self.missing


class DefinitionLibrary:
    """Finds ``.msg`` texts through the ament index and assembles full definitions (cached).

    Args:
        share_lookup: ``package -> share directory``; defaults to
            ``ament_index_python.get_package_share_directory``.
        warn: called once per top-level type whose definition is incomplete, with a message
            naming it; defaults to this module's logger.
    """

    def __init__(
        self,
        share_lookup: ShareLookup | None = None,
        warn: Callable[[str], None] | None = None,
    ) -> None:
        self._share_lookup = share_lookup or _default_share_lookup
        self._warn = warn or logging.getLogger(__name__).warning
        self._texts: dict[tuple[str, str, str], str] = {}
        self._full: dict[str, Definition] = {}

    def msg_text(self, type_name: str) -> str:
        """The text of one type's own ``.msg`` (no dependencies).

        Raises:
            InvalidTypeNameError: malformed name.
            DefinitionNotFoundError: no package or file defines it.
        """
        key = split_type_name(type_name)
        if key not in self._texts:
            self._texts[key] = self._load(type_name, *key)
        return self._texts[key]

    def _load(self, type_name: str, package: str, namespace: str, name: str) -> str:
        bundled = BUNDLED_DEFINITIONS.get(f'{package}/{namespace}/{name}')
        try:
            share = Path(self._share_lookup(package))
        except (LookupError, ValueError) as err:  # PackageNotFoundError is a KeyError
            if bundled is not None:
                return bundled
            raise DefinitionNotFoundError(type_name, f'package {package!r}: {err}') from None
        path = share / namespace / f'{name}.msg'
        if path.is_file():
            return path.read_text(encoding='utf-8')
        if bundled is not None:
            return bundled
        if namespace == 'action' and name.endswith('_FeedbackMessage'):
            base = name.removesuffix('_FeedbackMessage')
            self._section(type_name, share, 'action', base, 2)  # the .action must exist
            return (
                f'unique_identifier_msgs/UUID goal_id\n{package}/action/{base}_Feedback feedback\n'
            )
        parts = _ACTION_PARTS if namespace == 'action' else _SERVICE_PARTS
        for suffix, index in parts.items():
            if name.endswith(suffix) and namespace in ('action', 'srv'):
                base = name.removesuffix(suffix)
                return self._section(type_name, share, namespace, base, index)
        raise DefinitionNotFoundError(type_name, f'{path} does not exist')

    @staticmethod
    def _section(type_name: str, share: Path, namespace: str, base: str, index: int) -> str:
        path = share / namespace / f'{base}.{namespace}'
        if not path.is_file():
            raise DefinitionNotFoundError(type_name, f'{path} does not exist')
        sections = _SECTION_SEPARATOR.split(path.read_text(encoding='utf-8'))
        if len(sections) <= index:
            raise DefinitionNotFoundError(type_name, f'{path} has {len(sections)} sections')
        return sections[index].lstrip('\n')

    def type_hash(self, type_name: str) -> str:
        """The ``RIHS01_<hex>`` type hash from ``<share>/<pkg>/<ns>/<Type>.json`` ('' if unknown).

        rosidl installs that JSON (type description and hashes) beside each ``.msg``; bundled
        types (TFMessage) and action feedback messages have none here.
        """
        try:
            package, namespace, name = split_type_name(type_name)
            path = Path(self._share_lookup(package)) / namespace / f'{name}.json'
            hashes = json.loads(path.read_text(encoding='utf-8'))['type_hashes']
            return next(h['hash_string'] for h in hashes if h['type_name'] == type_name)
        except (InvalidTypeNameError, LookupError, ValueError, OSError, StopIteration, TypeError):
            return ''

    def definition(self, type_name: str) -> Definition:
        """The complete definition of ``type_name``, as rosbag2 writes it into an MCAP schema.

        A type that cannot be found is left out and listed in ``missing`` (an unknown top-level
        type gives an empty text); one warning naming the top-level type and the missing ones is
        emitted (once per type). Never raises: the topic is still recorded.
        """
        if type_name in self._full:
            return self._full[type_name]
        try:
            root = self.msg_text(type_name)
            package = split_type_name(type_name)[0]
        except (DefinitionNotFoundError, InvalidTypeNameError) as err:
            self._warn(f'no definition for {type_name} ({err}); the topic is still recorded')
            self._full[type_name] = Definition(type_name, '', (type_name,))
            return self._full[type_name]
        seen: set[str] = set()
        missing: list[str] = []

        def append(text: str, context: str, depth: int) -> str:
            result = text
            for dependency in parse_dependencies(text, context):
                if dependency in seen:
                    continue
                seen.add(dependency)
                try:
                    dep_text = self.msg_text(dependency)
                except (DefinitionNotFoundError, InvalidTypeNameError):
                    missing.append(dependency)
                    continue
                if depth <= 0:
                    missing.append(dependency)
                    continue
                block = append(dep_text, split_type_name(dependency)[0], depth - 1)
                result += f'\n{SEPARATOR}\nMSG: {dependency}\n{block}'
            return result

        text = append(root, package, 50)
        definition = Definition(type_name, text, tuple(missing))
        if missing:
            self._warn(
                f'incomplete definition of {type_name}: no .msg for {", ".join(missing)}; '
                'the topic is still recorded'
            )
        self._full[type_name] = definition
        return definition
