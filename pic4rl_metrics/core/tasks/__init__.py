"""The metrics of one task each, beside the navigation metrics every episode gets: following a
person (``person``), the social metrics of an episode with people (``crowd``). Each module
registers its columns when ``core.metrics`` imports it, in table order, and reads only ``core``
(``Derived``, the kinematics, the registry)."""
