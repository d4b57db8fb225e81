"""The MJCF worlds the tests write. Free of ROS."""

from __future__ import annotations

import textwrap


def walled_square_mjcf(half_m: float, inner: str = "", *, model: str = "arena") -> str:
    """A floor and four walls (1 m high, 0.1 m thick) whose inner faces bound the square
    [-half_m, half_m]², around ``inner``: the MJCF of the geoms and bodies inside it."""
    wall = half_m + 0.05
    lines = ['<geom name="floor" type="plane" size="0 0 0.05"/>']
    for name, pos, size in (("north", f"0 {wall:g}", f"{half_m + 0.1:g} 0.05"),
                            ("south", f"0 {-wall:g}", f"{half_m + 0.1:g} 0.05"),
                            ("east", f"{wall:g} 0", f"0.05 {half_m:g}"),
                            ("west", f"{-wall:g} 0", f"0.05 {half_m:g}")):
        lines.append(f'<geom name="{name}" type="box" pos="{pos} 0.5" size="{size} 0.5"/>')
    lines += textwrap.dedent(inner).strip("\n").splitlines()
    body = "\n".join("    " + line for line in lines)
    return f'<mujoco model="{model}">\n  <worldbody>\n{body}\n  </worldbody>\n</mujoco>\n'
