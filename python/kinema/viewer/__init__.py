"""A trajectory in the browser: three.js plays the frames with play/pause, scrubbing, speed,
an orbit camera framing the whole scene (in 3D kept above the floor: the lowest plane facing
up or closed box bottom), and the colour menu: ``speed`` and ``id`` (viridis, with a legend of
the least and greatest value shown), ``color`` (each particle's own, ``Trajectory.colors``:
an emitter's ``color``; the renderer's ``NO_OWN_COLOR`` for a particle without one; offered
when some particle has one) and ``none``. ``color_by=`` picks the colouring the page opens
with (a scene's ``[render] color_by``); by default speed. ``camera=`` (a scene's ``[render]
camera``: a ``kinema.Camera3D``, eye, target, up and vertical field of view, or a
``kinema.Camera2D``, the xy rectangle fitted centred) is the view the page opens with,
instead of the one it fits to the scene; ``kinema view SCENE.toml`` passes the scene's. The
page counts "1 particle", "N particles". The trajectory's colliders are
drawn (planes as floor patches, boxes as their edges less the open faces', sphere obstacles;
in 2D lines, rectangles and discs), its springs as lines, and only the particles alive at
each frame (births and deaths).

- ``write_html(traj, path)`` writes one self-contained HTML file (script and frames inlined)
  that plays offline.
- ``serve(traj)`` serves the page and its frames (``/data.bin``) on 127.0.0.1 at a free port
  and opens it in the user's browser when there is one.

The page's script is a bundle built from ``viewer/`` (three.js from the npm registry, bundled by
esbuild) into ``kinema/viewer/static/viewer.js`` by ``make viewer`` and committed; nothing is fetched from
the internet when a page is opened.
"""

from .page import BundleMissingError, ViewerWarning, write_html
from .server import serve

__all__ = ["BundleMissingError", "ViewerWarning", "serve", "write_html"]
