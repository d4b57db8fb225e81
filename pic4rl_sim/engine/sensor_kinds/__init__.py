"""pic4rl's own optional sensors beyond the LiDAR and the depth camera, one module each (the
paper's future-work sensors): a module holds its spec, its reader, its step messages and its
bridge decoding, and each of pic4rl's tables names them in one entry (``SENSOR_TABLE``,
``INTERFACE_TABLE``, ``SENSOR_MESSAGES``, ``READING_TABLE``). The tables import the module, never
the other way round (no import circle), so a module here imports no table. Kept apart from
``engine/`` itself, whose folder is full."""

#: Their kinds' names, in ``SENSOR_TABLE``'s order: their random streams come after the crowd's,
#: so that adding one leaves every earlier stream as it was.
NAMES = ("sonar", "uwb", "stereo")
#: An optical frame (z forward, x right, y down) in a body frame (x forward, y left, z up),
#: as a quaternion (x, y, z, w).
OPTICAL_XYZW = (-0.5, 0.5, -0.5, 0.5)


def optical(pitch_rad: float = 0.0) -> tuple[float, float, float, float]:
    """The optical frame of a camera pitched down by ``pitch_rad`` (about the body's +y), as a
    quaternion (x, y, z, w) in the body frame: the pitch, then ``OPTICAL_XYZW``."""
    import math

    bx, by, bz, bw = OPTICAL_XYZW
    ay, aw = math.sin(0.5 * pitch_rad), math.cos(0.5 * pitch_rad)
    return (aw * bx + ay * bz, aw * by + ay * bw, aw * bz - ay * bx, aw * bw - ay * by)


class Instant:
    """A sensor's last reading, kept for the instant it was made at: the robot's pose, the
    sim time and the random stream (an episode's), so that the several messages and readings
    of one instant share one draw of noise."""

    def __init__(self) -> None:
        self._last: tuple[object, tuple[float, ...], object] | None = None

    def get(self, rng: object, key: tuple[float, ...]) -> object | None:
        """The reading made with ``rng`` at ``key``, or ``None``."""
        last = self._last
        return last[2] if last is not None and last[0] is rng and last[1] == key else None

    def keep(self, rng: object, key: tuple[float, ...], reading: object) -> object:
        """Keep ``reading`` as made with ``rng`` at ``key``; returns it."""
        self._last = (rng, key, reading)
        return reading
