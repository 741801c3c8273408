"""Off-screen rendering of particle trajectories into frames, MP4 (H.264) and GIF.

2D scenes are drawn as antialiased discs seen from +z, 3D scenes as shaded spheres in
perspective, far to near. Particles are coloured by speed, by id, or by any per-particle field,
and each frame carries a time stamp. The world's colliders can be drawn with them
(`colliders=`): in 3D a plane is a translucent patch with a faint grid and a dark outline,
cut where other planes meet it (a bowl of planes shows its facets), a box its edges and a
lightly filled floor, a sphere obstacle a grey shaded sphere, and each particle casts a soft
contact shadow straight down on the floor below it, fading with its height; in 2D a plane is a thick line
with its solid side shaded, a box a rectangle outline, a sphere obstacle a grey disc; a
collider with a `motion` is drawn where it is at each frame's time. Pixels
are drawn by the engine (`kinema._core`, in parallel, with the GIL released); this module
chooses cameras and colours and writes files. Springs (`springs=`, pairs of particles) are
lines between the particles, and particles not alive in a frame (`alive=`, or NaN
positions: births and deaths) are left out, with their springs. Particles coloured by a
quantity get a colour bar with its name, units and range in the top right corner
(`legend=`). The default camera frames where the particles spend the run and where they
end, with the walls of the box they are in, into the frame's width and height, clear of the
legend, one view for the whole video.

    frames = render_frames(traj_x, radius=0.01, t=traj_t, dim=3, color_by="speed", colliders=world.colliders)
    write_video(frames, "out.mp4", fps=30, times=traj_t)  # exactly 30 fps, in real time

MP4s are BT.709, tagged so, with `moov` first; `video_rate` gives the exact frame rate a
file is written at (GIF delays are whole 1/100 s), `playback_rate` the default rate of a
recording (the fps it was recorded at, else the common rate within 2 %, else its own).

The package: `frames` (`render_frames`: colours, the live particles, springs, one call to
the engine per frame), `cameras` (`Camera2D`, `Camera3D` and the default camera that
fits the scene), `legend` (the colour bar), `descriptions` (colliders as the plain
descriptions `Trajectory.colliders` holds, which the engine takes: the names of
`kinema.collider_descriptions`, which the trajectory files and checkpoints share) and `video`
(`write_video`, `video_rate`, `playback_rate`: MP4 and GIF files).
"""

from __future__ import annotations

from .cameras import Camera2D, Camera3D
from .descriptions import _KIND as _KIND  # (kinema.collider_descriptions)
from .descriptions import _describe_colliders as _describe_colliders  # (kinema.collider_descriptions)
from .frames import COLORMAPS, low_end, render_frames
from .frames import NO_OWN_COLOR as NO_OWN_COLOR
from .frames import _trajectory_options as _trajectory_options  # Trajectory.render, kinema.runner
from .frames import own_colours as own_colours
from .video import COMMON_RATES, VIDEO_EXTENSIONS, playback_rate, video_rate, write_video
from .video import GIF_DELAYS_CS as GIF_DELAYS_CS

__all__ = ["Camera2D", "Camera3D", "COLORMAPS", "low_end", "render_frames", "write_video", "video_rate", "playback_rate", "COMMON_RATES", "VIDEO_EXTENSIONS"]
