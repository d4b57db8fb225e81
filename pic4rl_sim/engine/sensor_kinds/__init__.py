"""pic4rl's own optional sensors beyond the LiDAR and the depth camera, one module each (the
paper's future-work sensors): a module holds its spec, its reader, its step messages and its
bridge decoding, and each of pic4rl's tables names them in one entry (``SENSOR_TABLE``,
``INTERFACE_TABLE``, ``SENSOR_MESSAGES``, ``READING_TABLE``). The tables import the module, never
the other way round (no import circle), so a module here imports no table. Kept apart from
``engine/`` itself, whose folder is full."""

#: Their kinds' names, in ``SENSOR_TABLE``'s order: their random streams come after the crowd's,
#: so that adding one leaves every earlier stream as it was.
NAMES = ("sonar",)
