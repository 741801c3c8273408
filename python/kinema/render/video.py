"""Video files: `write_video` (MP4 through imageio-ffmpeg's ffmpeg: H.264, BT.709, tagged,
`moov` first; GIF through Pillow) and `video_rate`, the exact frame rate a file is
written at."""

from __future__ import annotations

import errno
import math
import numbers
import os
from collections.abc import Iterable, Iterator
from fractions import Fraction
from pathlib import Path

import numpy as np

from ..io._files import FileWriteError, os_errors_as_write_errors, write_error

#: File extensions ``write_video`` knows.
VIDEO_EXTENSIONS = (".mp4", ".gif")


def write_video(
    frames: Iterable[np.ndarray],
    path,
    fps: float = 30.0,
    *,
    times=None,
    preset: str = "ultrafast",
    crf: int = 20,
) -> Path:
    """Write RGB uint8 frames of one size to `path` and return it as a Path.

    The frame rate written is `video_rate(fps, path)`, exactly:

    - `.mp4`: `fps` as a fraction with a denominator of at most 1001 (30 → 30/1,
      29.97 → 2997/100, 30000/1001 stays; `fps` may be a `fractions.Fraction`), so a
      30 fps video says 30 fps, not 30.00003.
    - `.gif`: a GIF counts each frame's delay in whole 1/100 s, and browsers play a delay of
      0 or 1/100 s as 1/10 s: the delay is the whole number of 1/100 s from 2 to 65535 whose
      rate is closest to `fps` (ratio nearest 1), so 60 fps is written at 50 (2/100 s),
      30 fps at 33.3 (3/100 s), 25 at 25, 12 at 12.5 (8/100 s).

    `times` (seconds, increasing, one per frame; optional): the frames were recorded at these
    times and are to play in real time. The video is written at the rate above and each of its
    frames shows the recorded frame nearest in time to it (from `times[0]`, every 1/rate s up
    to the last time): frames are repeated or dropped where the recording interval differs from
    1/rate, and none are when it equals it (`World.run(fps=30)` records frame k at k/30 s: none
    dropped; a recording every 33 ms, 30.30 a second, loses one in about a hundred). Without
    `times`, each frame is one video frame at that rate (its playback speed is up to you).

    `.mp4`: H.264 (libx264, yuv420p, 4:2:0) by the ffmpeg that imageio-ffmpeg ships. The RGB
    is converted with the BT.709 matrix into limited ("tv") range by ffmpeg's scaler and the
    stream and the MP4 say so (`colr` box and H.264 VUI: primaries, transfer and matrix
    BT.709, limited range), so players convert it back with the same matrix; the `moov` box
    comes before the media data (`-movflags +faststart`), so a browser plays the file while
    it downloads. Odd sizes are padded by one edge row/column. x264 `preset` (ultrafast …
    veryslow; the default ultrafast keeps 10,000 particles at 1280×720 above 60 frames per
    second on two cores, `benchmarks/render.py`; slower presets give smaller files) and
    constant-quality `crf` (0 lossless … 51 worst).
    `.gif`: Pillow, looping, at most 256 colours a frame.

    The file is written under a temporary name in the same directory and renamed when
    complete: on any error nothing is left behind and an existing file is untouched. It gets
    the mode an ordinary `open()` gives a new file, 0666 less the umask (0644 under umask
    022), as every kinema writer's files do.

    A name the system cannot write is a `kinema.io.FileWriteError` (an `OSError`), one
    line naming `path`: a folder that does not exist (also a `FileNotFoundError`), a
    directory (also an `IsADirectoryError`), a name too long, a full disk.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in VIDEO_EXTENSIONS:
        raise ValueError(f"path = {str(path)!r} is invalid: the extension must be one of {', '.join(VIDEO_EXTENSIONS)}")
    rate = video_rate(fps, ext)
    counts = None if times is None else _repeats(times, rate)
    parent = path.parent if str(path.parent) else Path(".")
    from ..io._files import _temporary_file, refuse_special_target, remove_stale

    with os_errors_as_write_errors(path):  # a name too long, a folder not searchable: one line naming path
        if not parent.is_dir():
            raise write_error(path, errno.ENOENT, f"the folder {parent} does not exist")
        if path.is_dir():
            raise write_error(path, errno.EISDIR, f"it is a directory; give a file name such as {path / ('video' + ext)}")
        refuse_special_target(path)
        # The temporary file ends in the extension (ffmpeg picks its container by it) and is
        # created with mode 0666 less the umask, as open() creates files (tempfile.mkstemp's
        # 0600 stayed on the video: ffmpeg and Pillow write into the file that is there).
        remove_stale(parent, f".{path.name}.", f".part{ext}")  # left by a writer of it that was killed
        tmp = _temporary_file(parent, f".{path.name}.", f".part{ext}")
    try:
        stream = _checked(frames)
        if counts is not None:
            stream = _resampled(stream, counts)
        count = (_write_mp4 if ext == ".mp4" else _write_gif)(stream, tmp, rate, preset, crf)
        if count == 0:
            raise ValueError("frames is empty: a video needs at least one frame")
        if ext == ".mp4":
            _check_mp4(tmp, path, count)
        os.replace(tmp, path)
    except BaseException as e:
        tmp.unlink(missing_ok=True)
        if isinstance(e, OSError) and not isinstance(e, FileWriteError):
            raise _encoder_failure(path, e) from None
        raise
    return path


#: The frame rates a video of frames recorded within ``COMMON_RATE_TOLERANCE`` of one of them
#: defaults to (``playback_rate``).
COMMON_RATES = (24, 25, 30, 50, 60)
COMMON_RATE_TOLERANCE = 0.02


def playback_rate(times, fps=None, limits=None) -> tuple[float, bool, str]:
    """The default frame rate of a video of frames recorded at `times` (s), to play them in
    real time: `(rate, real_time, how)`, where `real_time` says whether the frames are
    to be placed by their times (`write_video(times=)`) and `how` says why, in words.

    - `fps`, the frames per second the recording was asked for (`Trajectory.fps`, from
      `World.run(fps=)` or an H5MD file kinema wrote), when the recording interval is
      its rounding to whole steps (from 1/1.5 to 1/0.5 of it): `World.run(fps=30)` records
      frame k at k/30 s and the video is 30 fps (an older kinema's recording every 33 steps
      of 1 ms, 30.30 frames a second, plays at 30 with one frame in about a hundred dropped).
    - Else the common rate (`COMMON_RATES`: 24, 25, 30, 50, 60) nearest the recording's
      rate, 1 / the median interval, when within 2 % of it (a file of another program,
      or of a kinema older than `fps` in its files).
    - Else the recording's rate; `limits` (lo, hi) clamp it, and a clamped rate is not
      real time (one video frame per recorded frame). A single frame: 30 fps (`fps` if
      given), not real time."""
    t = np.asarray(times, dtype=np.float64).reshape(-1)
    recorded = 1.0 / float(np.median(np.diff(t))) if t.size > 1 else float("nan")
    lo, hi = limits if limits is not None else (0.0, math.inf)
    known = isinstance(fps, numbers.Real) and not isinstance(fps, bool) and math.isfinite(fps) and lo <= fps <= hi and fps > 0
    if known and not math.isfinite(recorded):
        return float(fps), False, "a single frame"
    if known and 0.5 <= recorded / fps <= 1.5:
        return float(fps), True, f"real time, {recorded:.4g} recorded frames a second placed by their times"
    if not (math.isfinite(recorded) and recorded > 0):
        return 30.0, False, "one video frame per recorded frame"
    common = min(COMMON_RATES, key=lambda r: abs(recorded / r - 1.0))
    if abs(recorded / common - 1.0) <= COMMON_RATE_TOLERANCE:
        return float(common), True, f"real time at the common rate nearest the recording's {recorded:.4g} frames a second, placed by their times"
    rate = float(min(max(recorded, lo), hi))
    if rate == recorded:  # placed by their times: GIF delays round, the times need not be even
        return rate, True, "real time at the recording's rate"
    return rate, False, "one video frame per recorded frame"


#: GIF frame delays, in 1/100 s: browsers play 0 and 1 as 10, and the field has 16 bits.
GIF_DELAYS_CS = (2, 65535)


def video_rate(fps, path=".mp4") -> Fraction:
    """The exact frame rate `write_video` writes for `fps` into `path` (a file name or
    just its extension, ".mp4" or ".gif"), in frames per second: for MP4 `fps` as a fraction
    with a denominator up to 1001 (`video_rate(30) == 30`; below 1/1001, 1/n for n whole
    seconds a frame); for GIF 100/d, d the delay in 1/100 s from 2 to 65535 whose rate is
    nearest `fps` (`video_rate(60, ".gif") == 50`)."""
    if isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps = {fps!r} is invalid: frames per second must be a finite number > 0")
    ext = str(path).lower()
    ext = ext if ext in VIDEO_EXTENSIONS else Path(ext).suffix
    if ext not in VIDEO_EXTENSIONS:
        raise ValueError(f"path = {str(path)!r} is invalid: the extension must be one of {', '.join(VIDEO_EXTENSIONS)}")
    exact = Fraction(fps) if isinstance(fps, numbers.Rational) else Fraction(float(fps))
    if ext == ".gif":
        lo, hi = GIF_DELAYS_CS
        ideal = 100 / exact
        candidates = {min(max(d, lo), hi) for d in (math.floor(ideal), math.ceil(ideal))}
        delay = min(candidates, key=lambda d: (abs(math.log(d / ideal)), d))
        return Fraction(100, delay)
    if exact < Fraction(1, 1001):  # slower than a frame in 1001 s: a whole number of seconds a frame
        return Fraction(1, round(1 / exact))
    return exact.limit_denominator(1001)


def _repeats(times, rate: Fraction) -> np.ndarray:
    """How many video frames at `rate` each frame recorded at `times` fills, for playback
    in real time: video frame k (at times[0] + k/rate, k = 0 … round(span·rate)) shows the
    recorded frame nearest in time (the earlier one on a tie); 0 drops the frame."""
    t = np.asarray(times, dtype=np.float64)
    if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)):
        raise ValueError(f"times has shape {t.shape}: expected one finite time (s) per frame")
    if np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0)) + 1
        raise ValueError(f"times[{k}] = {t[k]!r} is invalid: times must increase (times[{k - 1}] = {t[k - 1]!r})")
    r = float(rate)
    n_out = int(round((t[-1] - t[0]) * r)) + 1
    # Video frames up to the midpoint between recorded frames i and i + 1 show frame i or one
    # before it; a relative 1e-9 settles ties that rounding would otherwise decide.
    mid = 0.5 * (t[:-1] + t[1:]) - t[0]
    upto = np.minimum(np.floor(mid * r * (1 + 1e-9)).astype(np.int64) + 1, n_out)
    return np.diff(np.concatenate([[0], upto, [n_out]]))


def _resampled(frames: Iterator[np.ndarray], counts: np.ndarray) -> Iterator[np.ndarray]:
    """Each frame repeated counts[k] times (0: left out)."""
    k = -1
    for k, f in enumerate(frames):
        if k >= counts.size:
            raise ValueError(f"frames has more frames than times ({counts.size}): give one time per frame")
        for _ in range(int(counts[k])):
            yield f
    if k + 1 != counts.size:
        raise ValueError(f"frames has {k + 1} frames and times {counts.size}: give one time per frame")


def _checked(frames: Iterable[np.ndarray]) -> Iterator[np.ndarray]:
    """The frames as C-contiguous (H, W, 3) uint8, all of the first one's size."""
    shape = None
    for k, f in enumerate(frames):
        f = np.asarray(f)
        if f.dtype != np.uint8 or f.ndim != 3 or f.shape[2] != 3:
            raise ValueError(f"frames[{k}] has dtype {f.dtype} and shape {f.shape}: expected uint8 (H, W, 3)")
        if shape is None:
            shape = f.shape
        elif f.shape != shape:
            raise ValueError(f"frames[{k}] has shape {f.shape}: all frames must have the first one's shape {shape}")
        yield np.ascontiguousarray(f)


#: What the MP4 says about its colours, and the conversion that makes it true: ffmpeg's
#: scaler converts the RGB frames with the BT.709 matrix into limited range (the tags alone
#: would not change the matrix), then x264 and the MP4 muxer record the same description.
_MP4_COLOUR = [
    "-vf",
    "scale=out_color_matrix=bt709:out_range=tv:flags=bicubic+accurate_rnd,format=yuv420p,"
    "setparams=colorspace=bt709:color_primaries=bt709:color_trc=bt709:range=tv",
    "-colorspace",
    "bt709",
    "-color_primaries",
    "bt709",
    "-color_trc",
    "bt709",
    "-color_range",
    "tv",
]


def _encoder_failure(path: Path, e: OSError | None) -> FileWriteError:
    """The error of a video the encoder could not finish: the system's reason where the
    encoder's pipe or file told it, else ENOSPC when the folder is full, else EIO."""
    import errno
    import shutil

    if e is not None and e.errno is not None and e.errno != errno.EPIPE:
        return FileWriteError.of(path, e)
    parent = path.parent if str(path.parent) else Path(".")
    full = shutil.disk_usage(parent).free < 1 << 20
    code = errno.ENOSPC if full else errno.EIO
    reason = os.strerror(code) if full else "the video encoder (ffmpeg) did not finish the file"
    return FileWriteError(code, reason, os.fspath(path))


def _check_mp4(tmp: Path, path: Path, count: int) -> None:
    """The MP4 at `tmp` holds all `count` frames, or raises `FileWriteError`: ffmpeg's
    exit status is not reported through imageio-ffmpeg's writer, and a disk that fills while
    it writes the last packets or the index (moov) leaves a file no player opens."""
    import imageio_ffmpeg

    try:
        frames, _ = imageio_ffmpeg.count_frames_and_secs(str(tmp))
    except (RuntimeError, OSError):
        frames = -1
    if frames != count:
        raise _encoder_failure(path, None)


def _write_mp4(frames: Iterator[np.ndarray], tmp: Path, rate: Fraction, preset: str, crf: int) -> int:
    import imageio_ffmpeg

    writer = None
    count = 0
    try:
        for f in frames:
            h, w = f.shape[:2]
            if h % 2 or w % 2:
                # yuv420p stores colour at half resolution: both sides must be even.
                f = np.pad(f, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
            if writer is None:
                writer = imageio_ffmpeg.write_frames(
                    str(tmp),
                    (f.shape[1], f.shape[0]),
                    pix_fmt_in="rgb24",
                    fps=rate,
                    codec="libx264",
                    quality=None,
                    macro_block_size=1,
                    output_params=["-preset", str(preset), "-crf", str(int(crf)), *_MP4_COLOUR, "-movflags", "+faststart"],
                    ffmpeg_log_level="error",
                )
                writer.send(None)
            writer.send(f)
            count += 1
    finally:
        if writer is not None:
            writer.close()
    return count


def _write_gif(frames: Iterator[np.ndarray], tmp: Path, rate: Fraction, preset: str, crf: int) -> int:
    from PIL import Image

    count = 0

    def images():
        nonlocal count
        for f in frames:
            count += 1
            yield Image.fromarray(f)

    it = images()
    first = next(it, None)
    if first is None:
        return 0
    # rate is 100/d (video_rate): d/100 s a frame, given to Pillow in ms.
    delay_ms = round(1000 / rate)
    first.save(tmp, format="GIF", save_all=True, append_images=it, duration=delay_ms, loop=0)
    return count
