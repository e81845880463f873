"""Reading JSON that a user or a web page wrote: one depth check before ``json.loads``.

``json.loads`` recurses once per bracket, so a few thousand ``[`` end in a
``RecursionError`` deep inside the parser. Scene files (:mod:`brdfkit.render.scene`)
and the explorer server's query values (:mod:`brdfkit.web.server`) call
:func:`nesting_exceeds` first and answer with their own one-line error.
"""

from __future__ import annotations

__all__ = ["nesting_exceeds"]


def nesting_exceeds(text: str, limit: int) -> bool:
    """Whether the brackets of JSON ``text`` nest deeper than ``limit`` (brackets inside strings skipped)."""
    depth, in_str, esc = 0, False, False
    for ch in text:
        if in_str:
            if esc:
                esc = False
            elif ch == "\\":
                esc = True
            elif ch == '"':
                in_str = False
        elif ch == '"':
            in_str = True
        elif ch in "[{":
            depth += 1
            if depth > limit:
                return True
        elif ch in "]}":
            depth -= 1
    return False
