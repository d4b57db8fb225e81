"""setuptools' build backend, with editable installs that keep ``data-files``.

setuptools (65 to at least 84.2.1) builds an editable wheel asking ``Distribution.has_data()``,
which does not exist (the method is ``has_data_files``), so ``pip install -e .`` silently
drops ``[tool.setuptools.data-files]``: the ament index entries that let ``ros2 run
pic4rl_sim sim`` find the node. Regular wheels are unaffected. Remove this shim once
setuptools fixes the call.
"""

from setuptools.build_meta import *  # noqa: F403  (the whole PEP 517/660 interface)
from setuptools.dist import Distribution

if not hasattr(Distribution, "has_data"):
    Distribution.has_data = Distribution.has_data_files  # type: ignore[attr-defined]
