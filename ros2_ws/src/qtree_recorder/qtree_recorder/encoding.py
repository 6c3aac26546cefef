"""CDR encoding from definition text, for messages without Python typesupport (no rclpy).

There is no tf2_msgs wheel, so ``/tf`` and ``/tf_static`` (``tf2_msgs/msg/TFMessage``) are encoded
with ``mcap_ros2``'s dynamic encoder from the full definition text. Messages are plain nested
``dict``/``list`` values; ``mcap_ros2`` rejects numpy arrays (foxglove/mcap#1469), so
:func:`to_builtin` converts them (and numpy scalars, tuples) first.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from mcap_ros2._dynamic import serialize_dynamic

from qtree_recorder.definitions import DefinitionLibrary
from qtree_recorder.exceptions import EncodingError

Encoder = Callable[[Any], bytes]


def to_builtin(value: Any) -> Any:
    """Convert numpy arrays/scalars and tuples inside ``value`` to lists and Python numbers."""
    if isinstance(value, Mapping):
        return {k: to_builtin(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_builtin(v) for v in value]
    tolist = getattr(value, 'tolist', None)  # numpy arrays and numpy scalars
    if callable(tolist):
        return to_builtin(tolist())
    return value


class DynamicEncoder:
    """Encode dict messages to CDR bytes from their ``ros2msg`` definitions (encoders cached).

    Args:
        definitions: source of the full definition texts.
    """

    def __init__(self, definitions: DefinitionLibrary | None = None) -> None:
        self._definitions = definitions or DefinitionLibrary()
        self._encoders: dict[str, Encoder] = {}

    def encoder(self, type_name: str) -> Encoder:
        """The encoder function of ``type_name``.

        Raises:
            EncodingError: the definition is incomplete or cannot be parsed.
        """
        if type_name not in self._encoders:
            definition = self._definitions.definition(type_name)
            if not definition.complete:
                missing = ', '.join(definition.missing)
                raise EncodingError(type_name, ValueError(f'no definition for {missing}'))
            try:
                encoders = serialize_dynamic(type_name, definition.text)
            except Exception as err:  # mcap_ros2 raises plain exceptions on bad text
                raise EncodingError(type_name, err) from None
            self._encoders[type_name] = encoders[type_name]
        return self._encoders[type_name]

    def encode(self, type_name: str, message: Mapping[str, Any]) -> bytes:
        """Serialise ``message`` (nested dicts/lists; numpy allowed) to CDR.

        Raises:
            EncodingError: unknown type or a value that does not fit its field.
        """
        encode = self.encoder(type_name)
        try:
            return bytes(encode(to_builtin(message)))
        except Exception as err:  # field type mismatches surface as various exceptions
            raise EncodingError(type_name, err) from None
