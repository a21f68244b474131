"""mkdocs hook: the Experiments page's pictures, rendered by the docs build itself.

Each experiment runs briefly on the Fast backend (seed 0) and :class:`dream.viz.Renderer`
draws its last frame into ``img/<name>.png`` of the site, so the pictures always show what
this version of DREAM does. The whole hook takes a few seconds.
"""

from __future__ import annotations

import io
import logging

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import File, Files

import dream
from dream.experiments import EXPERIMENTS
from dream.frames import Frame
from dream.viz import Renderer

log = logging.getLogger(f"mkdocs.hooks.{__name__}")

#: Steps run before the picture: long enough for each team to be visibly under way.
STEPS = {"hrvo-circle": 400, "line-consensus": 900, "voronoi-coverage": 300, "affine-formation": 700}
DEFAULT_STEPS = 500  #: for an experiment added later


def frame_png(name: str) -> bytes:
    """PNG bytes of experiment ``name``'s last frame after a short run on the Fast backend."""
    last: list[Frame] = []

    def keep(frame: Frame) -> None:
        last[:] = [frame]

    dream.run(EXPERIMENTS[name], seed=0, backend="fast", steps=STEPS.get(name, DEFAULT_STEPS), record=keep)
    renderer = Renderer(last[0].arena)
    renderer.draw(last[0])
    image = io.BytesIO()
    renderer.figure.savefig(image, format="png")
    return image.getvalue()


def on_files(files: Files, config: MkDocsConfig) -> Files:
    for name in sorted(EXPERIMENTS):
        files.append(File.generated(config, f"img/{name}.png", content=frame_png(name)))
        log.info("rendered img/%s.png", name)
    return files
