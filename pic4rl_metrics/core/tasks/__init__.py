"""The metrics of one task each, beside the navigation metrics every episode gets: following a
person (``person``), the social metrics of an episode with people (``crowd``), the area an
exploration has seen (``coverage``, integrated by ``seen`` while a bag is read). Each module
registers its columns when ``core.metrics`` imports it, in table order, and reads only ``core``
(``Derived``, the kinematics, the registry)."""
