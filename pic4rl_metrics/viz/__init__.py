"""Pictures: figures (``plots``), drawing on arrays (``raster``), episode videos (``video``,
``video_batch``) and the one-page HTML report (``html_report`` with ``html_page``,
``report_maps``, ``report_logs``, ``report_inputs`` and ``report_export``). Matplotlib,
Pillow and imageio load only here.
"""

from __future__ import annotations

from pic4rl_base.lazy import lazy_exports

_HOMES = {
    "episode_figure": "plots", "trajectories_figure": "plots", "View": "raster",
    "EpisodeScene": "video", "render_videos": "video_batch", "write_report": "html_report",
}
__getattr__, __dir__ = lazy_exports(__name__, _HOMES, namespace=globals())
__all__ = sorted(_HOMES)
