"""The MP4 and GIF files kinema writes, as other tools read them: the colour description and the
conversion it describes, `moov` before `mdat` (faststart), the exact frame rate, and GIF delays.

The outside tool is the ffmpeg binary of imageio-ffmpeg (its stderr and its decoded frames);
the MP4 boxes are read here; GIF delays with Pillow. Videos are small (64×48) and short.
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import struct
import subprocess
from fractions import Fraction
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest
from PIL import Image

import kinema
from kinema.cli import app
from kinema.render import Camera2D, render_frames, video_rate, write_video
from kinema.runner import _render_video

FFMPEG = imageio_ffmpeg.get_ffmpeg_exe()
W, H = 64, 48

# Saturated primaries (the largest BT.601/BT.709 mismatch), viridis' ends and middle (the
# default colormap), a grey, an orange.
COLOURS = [(255, 0, 0), (0, 255, 0), (0, 0, 255), (68, 1, 84), (33, 145, 140), (253, 231, 37), (128, 128, 128), (200, 100, 50)]


# -- reading the files --------------------------------------------------------------------------


def boxes(data: bytes, start: int = 0, end: int | None = None) -> list[tuple[bytes, int, int]]:
    """The MP4 boxes in data[start:end]: (type, payload start, box end)."""
    end = len(data) if end is None else end
    out = []
    i = start
    while i + 8 <= end:
        size, kind = struct.unpack(">I4s", data[i : i + 8])
        header = 8
        if size == 1:
            size, header = struct.unpack(">Q", data[i + 8 : i + 16])[0], 16
        elif size == 0:
            size = end - i
        assert size >= header and i + size <= end, f"broken box {kind!r} at {i}"
        out.append((kind, i + header, i + size))
        i += size
    return out


def child(data: bytes, parent: tuple[bytes, int, int], *path: bytes) -> tuple[bytes, int, int]:
    for kind in path:
        found = [b for b in boxes(data, parent[1], parent[2]) if b[0] == kind]
        assert found, f"no {kind!r} box"
        parent = found[0]
    return parent


def mp4_timing(path) -> tuple[Fraction, int]:
    """(frame rate, frames) from the video track's mdhd time scale and stts sample durations;
    fails unless every frame lasts the same."""
    data = path.read_bytes()
    moov = next(b for b in boxes(data) if b[0] == b"moov")
    trak = child(data, moov, b"trak")
    mdhd = child(data, trak, b"mdia", b"mdhd")
    version = data[mdhd[1]]
    timescale = struct.unpack(">I", data[mdhd[1] + (20 if version == 1 else 12) :][:4])[0]
    stts = child(data, trak, b"mdia", b"minf", b"stbl", b"stts")
    (n_entries,) = struct.unpack(">I", data[stts[1] + 4 : stts[1] + 8])
    entries = [struct.unpack(">II", data[stts[1] + 8 + 8 * k : stts[1] + 16 + 8 * k]) for k in range(n_entries)]
    deltas = {delta for count, delta in entries if count}
    frames = sum(count for count, _ in entries)
    # The last frame's duration may be the muxer's guess; all others must agree.
    if len(entries) > 1 and entries[-1][0] == 1:
        deltas = {delta for count, delta in entries[:-1]}
    assert len(deltas) == 1, f"frames of unequal durations: {entries}"
    return Fraction(timescale, deltas.pop()), frames


def colr(path) -> tuple[int, int, int, bool]:
    """(primaries, transfer, matrix, full range) of the MP4's nclx colr box."""
    data = path.read_bytes()
    moov = next(b for b in boxes(data) if b[0] == b"moov")
    i = data.find(b"colrnclx", moov[1], moov[2])
    assert i >= 0, "the MP4 has no colr (nclx) box"
    p, t, m = struct.unpack(">HHH", data[i + 8 : i + 14])
    return p, t, m, bool(data[i + 14] & 0x80)


def ffmpeg_info(path) -> str:
    """The video stream line of ``ffmpeg -i path``."""
    err = subprocess.run([FFMPEG, "-hide_banner", "-i", str(path)], capture_output=True, text=True).stderr
    lines = [line for line in err.splitlines() if "Video:" in line]
    assert len(lines) == 1, err
    return lines[0]


def decode(path, vf: str | None = None, size=(W, H)) -> np.ndarray:
    """All frames decoded by ffmpeg to rgb24, (F, H, W, 3); ``vf`` filters first."""
    cmd = [FFMPEG, "-v", "error", "-i", str(path)]
    if vf:
        cmd += ["-vf", vf]
    out = subprocess.run([*cmd, "-f", "rawvideo", "-pix_fmt", "rgb24", "-"], capture_output=True, check=True).stdout
    return np.frombuffer(out, np.uint8).reshape(-1, size[1], size[0], 3)


def solid(c) -> np.ndarray:
    return np.full((H, W, 3), c, np.uint8)


# -- MP4: colour --------------------------------------------------------------------------------


def test_mp4_is_tagged_bt709_limited_range(tmp_path):
    path = write_video([solid(c) for c in COLOURS], tmp_path / "c.mp4", fps=30)
    # 1 = BT.709 for primaries, transfer and matrix (ISO/IEC 23091-2); limited range.
    assert colr(path) == (1, 1, 1, False)
    assert re.search(r"yuv420p\(tv, bt709[,)]", ffmpeg_info(path)), ffmpeg_info(path)
    trace = subprocess.run(
        [FFMPEG, "-hide_banner", "-i", str(path), "-c", "copy", "-bsf:v", "trace_headers", "-f", "null", "-"], capture_output=True, text=True
    ).stderr
    vui = {k: int(v) for k, v in re.findall(r"(colour_primaries|transfer_characteristics|matrix_coefficients|video_full_range_flag)\s+\S+ = (\d+)", trace)}
    assert vui == {"colour_primaries": 1, "transfer_characteristics": 1, "matrix_coefficients": 1, "video_full_range_flag": 0}, vui


@pytest.mark.parametrize("how", ["as tagged", "as BT.709"])
def test_mp4_colours_decode_back_within_2_levels(tmp_path, how):
    # "as tagged": ffmpeg picks the matrix from the file. "as BT.709": the matrix is forced, as
    # a player that assumes BT.709 for HD video does: this checks the conversion itself, not
    # just the tag (BT.601 data read as BT.709 is 10 to 41 levels off for these colours).
    frames = [solid(c) for c in COLOURS]
    path = write_video(frames, tmp_path / "c.mp4", fps=30)
    vf = "scale=in_color_matrix=bt709:in_range=tv" if how == "as BT.709" else None
    got = decode(path, vf)
    assert got.shape[0] == len(COLOURS)
    err = np.abs(got.astype(int) - np.array(frames, dtype=int)).max(axis=(1, 2, 3))
    assert err.max() <= 2, dict(zip(COLOURS, err.tolist(), strict=True))


def test_rendered_particle_and_background_keep_their_colours(tmp_path):
    # One frame from render_frames, 128×96: a disc of viridis' middle colour (fixed) 60 px
    # across on a dark purple background; the solid 16×16 blocks at the disc's centre and in
    # the corner (away from edges, where H.264 leaves ringing) decode to the rendered pixels.
    disc, background = (33, 145, 140), (68, 1, 84)
    frame = next(
        render_frames(
            np.zeros((1, 1, 2)), 0.7, [0.0], dim=2, color_by=np.array([disc], np.uint8), camera=Camera2D(-1.5, -1, 1.5, 1),
            width=128, height=96, background=background, time_format=None,
        )
    )  # fmt: skip
    inside, corner = frame[40:56, 56:72], frame[0:16, 0:16]
    assert (inside == disc).all() and (corner == background).all()
    path = write_video([frame, frame], tmp_path / "r.mp4", fps=10)
    got = decode(path, "scale=in_color_matrix=bt709:in_range=tv", size=(128, 96))[0].astype(int)
    assert np.abs(got[40:56, 56:72] - inside).max() <= 2
    assert np.abs(got[0:16, 0:16] - corner).max() <= 2


# -- MP4: faststart -----------------------------------------------------------------------------


def test_mp4_moov_comes_before_mdat(tmp_path):
    path = write_video([solid((10 * k, 0, 0)) for k in range(20)], tmp_path / "f.mp4", fps=30)
    kinds = [kind for kind, _, _ in boxes(path.read_bytes())]
    assert kinds[0] == b"ftyp" and b"moov" in kinds and b"mdat" in kinds
    assert kinds.index(b"moov") < kinds.index(b"mdat"), kinds


# -- MP4: frame rate ----------------------------------------------------------------------------


@pytest.mark.parametrize(("fps", "rate", "shown"), [(30, Fraction(30), "30 fps"), (30.0, Fraction(30), "30 fps"), (Fraction(30000, 1001), Fraction(30000, 1001), "29.97 fps"), (29.97, Fraction(2997, 100), "29.97 fps"), (12, Fraction(12), "12 fps")])  # fmt: skip
def test_mp4_frame_rate_is_exactly_the_one_asked_for(tmp_path, fps, rate, shown):
    assert video_rate(fps) == rate
    path = write_video([solid((5 * k, 0, 0)) for k in range(12)], tmp_path / "r.mp4", fps=fps)
    assert mp4_timing(path) == (rate, 12)
    assert f", {shown}," in ffmpeg_info(path), ffmpeg_info(path)


def test_frames_placed_by_their_times_play_in_real_time_at_the_rate_asked(tmp_path):
    # World.run(fps=30) with dt = 1 ms records every 33 steps: 30.30 frames a second. With
    # their times the video is exactly 30 fps, each video frame the recorded one nearest in time.
    t = np.arange(101) * 0.033  # 3.3 s
    frames = [solid((20 + 20 * (k % 10), 20 + 20 * (k // 10), 0)) for k in range(t.size)]
    path = write_video(frames, tmp_path / "rt.mp4", fps=30, times=t)
    rate, n = mp4_timing(path)
    assert rate == 30 and n == 100  # 3.3 s at 30 fps, both ends included
    got = decode(path)[:, H // 2, W // 2].astype(int)
    shown = np.round((got[:, 0] - 20) / 20).astype(int) + 10 * np.round((got[:, 1] - 20) / 20).astype(int)
    expected = [int(np.argmin(np.abs(t - k / 30))) for k in range(n)]
    assert shown.tolist() == expected
    assert len(set(expected)) == 100  # one recorded frame dropped, none repeated

    # A recording interval of exactly 1/fps: one video frame per recorded frame, none dropped.
    t = np.arange(40) * (100 * (1 / 3000))  # 100 steps of dt = 1/3000 s
    path = write_video(frames[:40], tmp_path / "exact.mp4", fps=30, times=t)
    assert mp4_timing(path) == (30, 40)
    got = decode(path)[:, H // 2, W // 2].astype(int)
    assert np.abs(got - np.array([f[0, 0] for f in frames[:40]], dtype=int)).max() <= 2


def test_kinema_run_writes_the_scene_fps_and_says_so(tmp_path):
    from typer.testing import CliRunner

    scene = tmp_path / "s.toml"
    # dt = 0.01 s and fps = 30: frame k at k/30 s (4 steps of 8.3 ms a frame).
    scene.write_text(
        '[world]\ndim = 2\ndt = 0.01\nduration = 3.0\nfps = 30.0\n\n[[particles]]\ntype = "list"\npositions = [[0, 1]]\nradius = 0.1\n\n'
        "[render]\nwidth = 64\nheight = 48\n\n[output]\ntrajectory = false\nplot = false\n"
    )
    res = CliRunner().invoke(app, ["run", str(scene), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    assert "video: 30 fps, real time" in res.output
    assert mp4_timing(tmp_path / "out" / "s.mp4") == (30, 91)  # 3.0 s at 30 fps

    # [render].fps is a playback rate: one video frame per recorded frame at exactly that rate.
    scene.write_text(scene.read_text().replace("height = 48\n", "height = 48\nfps = 10\n"))
    res = CliRunner().invoke(app, ["run", str(scene), "-o", str(tmp_path / "slow")])
    assert res.exit_code == 0, res.output
    assert "video: 10 fps, one video frame per recorded frame" in res.output
    assert mp4_timing(tmp_path / "slow" / "s.mp4") == (10, 91)


def _scene(tmp_path, fps=30.0, dt=1e-3, duration=1.0) -> Path:
    scene = tmp_path / "s.toml"
    scene.write_text(
        f'[world]\ndim = 2\ndt = {dt!r}\nduration = {duration!r}\nfps = {fps!r}\n\n[[particles]]\ntype = "list"\npositions = [[0, 1]]\n'
        "velocity = [1.0, 0.0]\nradius = 0.1\n\n[render]\nwidth = 64\nheight = 48\n\n[output]\nvideo = false\nplot = false\n"
    )
    return scene


def _run_and_save(tmp_path, **scene) -> Path:
    from typer.testing import CliRunner

    res = CliRunner().invoke(app, ["run", str(_scene(tmp_path, **scene)), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    return tmp_path / "out" / "trajectory.h5"


def test_kinema_render_of_a_saved_run_plays_at_the_scene_fps(tmp_path):
    # fps = 30 and dt = 1 ms record frame k at k/30 s; the file says the scene's 30
    # (/parameters/kinema fps), and the video is 30 fps in real time (it was 1000/33 = 30.30
    # fps when frames came every 33 steps).
    from typer.testing import CliRunner

    saved = _run_and_save(tmp_path)
    traj = kinema.Trajectory.load(saved)
    assert traj.fps == 30.0 and traj.t.size == 31 and traj.t[1] == 1 / 30
    res = CliRunner().invoke(app, ["render", str(saved), "-o", str(tmp_path / "v.mp4"), "--width", "64", "--height", "48"])
    assert res.exit_code == 0, res.output
    assert "video: 30 fps, real time, 30 recorded frames a second placed by their times" in res.output
    path = tmp_path / "v.mp4"
    assert mp4_timing(path) == (30, round(traj.t[-1] * 30) + 1)  # 0.99 s at 30 fps, both ends
    assert imageio_ffmpeg.read_frames(str(path)).__next__()["fps"] == 30.0
    assert ", 30 fps," in ffmpeg_info(path)
    ffprobe = shutil.which("ffprobe")
    if ffprobe is not None:
        out = subprocess.run([ffprobe, "-v", "error", "-select_streams", "v:0", "-show_entries", "stream=r_frame_rate,avg_frame_rate", "-of", "csv=p=0", str(path)],
                             capture_output=True, text=True, check=True).stdout  # fmt: skip
        assert out.split() == ["30/1,30/1"], out
    # --fps is still a playback rate: every recorded frame at exactly that rate.
    res = CliRunner().invoke(app, ["render", str(saved), "-o", str(tmp_path / "f.mp4"), "--width", "64", "--height", "48", "--fps", "10"])
    assert res.exit_code == 0, res.output
    assert mp4_timing(tmp_path / "f.mp4") == (10, traj.t.size)


def test_a_trajectory_without_fps_plays_at_the_common_rate_within_2_percent(tmp_path):
    # Another program's file (or an older kinema's) does not say its fps: 30.30 recorded frames
    # a second are within 2 % of 30, so the video is 30 fps in real time (it was 1000/33).
    w = kinema.World(dt=1e-3, dim=2)
    w.add_particles([[0.0, 0.0, 0.0]], radius=0.1)
    traj = w.run(0.5, fps=30)  # every 33 ms
    traj.fps = None
    path = _render_video(traj, tmp_path / "common.mp4", {"width": W, "height": H}, None, "rendering")
    assert mp4_timing(path) == (30, round(traj.t[-1] * 30) + 1)
    path = traj.render(tmp_path / "common2.mp4", width=W, height=H)  # the same default
    assert mp4_timing(path) == (30, round(traj.t[-1] * 30) + 1)
    # 60 asked at dt = 1 ms records every 17 steps, 58.82 a second: within 2 % of 60.
    assert kinema.render.playback_rate(np.arange(10) * 0.017)[:2] == (60.0, True)


def test_a_trajectory_far_from_the_common_rates_is_written_at_its_own_rate_exactly(tmp_path):
    # Every 1/22.2 s: 7.5 % from 24, so the recording's own rate, 22.2 = 111/5.
    w = kinema.World(dt=1e-3, dim=2)
    w.add_particles([[0.0, 0.0, 0.0]], radius=0.1)
    traj = w.run(0.5, fps=22.2)
    assert traj.t[1] == 1 / 22.2
    traj.fps = None
    path = _render_video(traj, tmp_path / "own.mp4", {"width": W, "height": H}, None, "rendering")
    assert mp4_timing(path) == (Fraction(111, 5), traj.t.size)


@pytest.mark.parametrize(("mask", "mode"), [(0o022, 0o644), (0o027, 0o640)], ids=["umask022", "umask027"])
def test_kinema_render_files_follow_the_umask(tmp_path, mask, mode):
    # They were 0600 (tempfile.mkstemp's mode, kept by ffmpeg and Pillow writing into it); every
    # other kinema writer gives 0666 less the umask.
    from typer.testing import CliRunner

    saved = _run_and_save(tmp_path)
    old = os.umask(mask)
    try:
        for name in ("v.mp4", "v.gif"):
            res = CliRunner().invoke(app, ["render", str(saved), "-o", str(tmp_path / name), "--width", "64", "--height", "48"])
            assert res.exit_code == 0, res.output
        write_video([solid((0, 0, 0))] * 2, tmp_path / "w.mp4")
        write_video([solid((0, 0, 0))] * 2, tmp_path / "old.gif")
        write_video([solid((9, 9, 9))] * 2, tmp_path / "old.gif")  # over an existing file
    finally:
        os.umask(old)
    for name in ("v.mp4", "v.gif", "w.mp4", "old.gif"):
        assert stat.S_IMODE((tmp_path / name).stat().st_mode) == mode, name
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []  # no temporary left


def test_bad_times_are_refused_and_leave_nothing(tmp_path):
    frames = [solid((0, 0, 0))] * 3
    with pytest.raises(ValueError, match="times"):
        write_video(frames, tmp_path / "a.mp4", times=[0.0, 0.1])
    with pytest.raises(ValueError, match="times"):
        write_video(frames, tmp_path / "a.mp4", times=[0.0, 0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match=r"times\[2\]"):
        write_video(frames, tmp_path / "a.gif", times=[0.0, 0.1, 0.1])
    with pytest.raises(ValueError, match="times"):
        write_video(frames, tmp_path / "a.mp4", times=[0.0, np.nan, 0.2])
    assert list(tmp_path.iterdir()) == []


# -- GIF ----------------------------------------------------------------------------------------


def gif_delays_ms(path) -> list[int]:
    with Image.open(path) as im:
        out = []
        for k in range(im.n_frames):
            im.seek(k)
            out.append(im.info["duration"])
        return out


@pytest.mark.parametrize(
    ("fps", "delay_ms"),
    [(60, 20), (100, 20), (1000, 20), (50, 20), (30, 30), (25, 40), (24, 40), (12, 80), (10, 100), (0.01, 100000), (0.001, 655350)],
)
def test_gif_delays_are_the_nearest_playable_ones(tmp_path, fps, delay_ms):
    # Whole 1/100 s, at least 2/100 s (browsers play 0 and 1 as 1/10 s), the rate nearest fps.
    frames = [solid((40 * k, 0, 0)) for k in range(5)]
    path = write_video(frames, tmp_path / "g.gif", fps=fps)
    assert gif_delays_ms(path) == [delay_ms] * 5
    assert video_rate(fps, path) == Fraction(1000, delay_ms)


def test_gif_with_times_plays_in_real_time_at_its_rate(tmp_path):
    # 60 frames a second asked, 50 written (2/100 s): frames recorded 1/60 s apart over 1 s are
    # placed by their times, 51 GIF frames for 1 s, some recorded frames dropped.
    t = np.arange(61) / 60
    frames = [solid((4 * k, 255 - 4 * k, 0)) for k in range(t.size)]
    path = write_video(frames, tmp_path / "g.gif", fps=60, times=t)
    delays = gif_delays_ms(path)
    assert set(delays) == {20} and len(delays) == 51
    with Image.open(path) as im:
        shown = []
        for k in range(im.n_frames):
            im.seek(k)
            shown.append(int(np.asarray(im.convert("RGB"))[0, 0, 0]) // 4)
    assert shown == [int(np.argmin(np.abs(t - k / 50))) for k in range(51)]


def test_trajectory_gif_plays_in_real_time(tmp_path):
    # Recorded at k/30 s, written at 100/3 (3/100 s a frame): placed by their times, 1.98 s
    # make 67 GIF frames, 2.01 s with the last one (not 60 frames, 1.8 s).
    w = kinema.World(dt=1e-3, dim=2)
    w.add_particles([[0.0, 0.0, 0.0]], velocity=[[1.0, 0.0, 0.0]], radius=0.1)
    traj = w.run(1.98, fps=30)
    assert traj.t.size == 60
    path = traj.render(tmp_path / "t.gif", width=W, height=H)
    delays = gif_delays_ms(path)
    assert sum(delays) == 67 * 30 and set(delays) == {30, 60}  # Pillow merges a repeated frame into one of 60 ms
