"""Clipping of echoed request text (no ROS)."""

from hypothesis import given
from hypothesis import strategies as st
from qtree_node_support.text import clip, quote


@given(st.text(), st.integers(1, 200))
def test_clip_is_bounded_and_keeps_short_text(text: str, limit: int) -> None:
    out = clip(text, limit)
    assert len(out) <= limit
    assert out == text if len(text) <= limit else out.endswith('…') and text.startswith(out[:-1])


def test_quote_cuts_long_strings_with_their_length() -> None:
    assert quote('O1') == "'O1'"
    long = quote('x' * 10_000)
    assert long == "'" + 'x' * 40 + "…' (10000 characters)"
    assert quote(5) == '5'
    assert len(quote('y' * 41, shown=40)) <= 40 + 30
