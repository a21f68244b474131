"""The renderer, the video writer and the recorder, on frames built here (no experiment run)."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import imageio_ffmpeg
import numpy as np
import pytest
from PIL import Image

import dream
from dream import Experiment
from dream.frames import TITLE_LENGTH, Frame, measures_title
from dream.specs import ROBOTARIUM, ArenaSpec
from dream.viz import Recorder, Renderer, VideoWriter, robot_colours

OBSTACLE = np.array([[-0.3, -0.3], [0.3, -0.3], [0.3, 0.3], [-0.3, 0.3]])


def make_frame(n: int = 4, step: int = 0, shift: float = 0.0, **overrides) -> Frame:
    """Robots on a row at y = 0.6 (robot 0 moved right by ``shift``) with every overlay."""
    x = np.linspace(-1.2, 1.2, n) if n > 1 else np.zeros(n)
    poses = np.vstack((x, np.full(n, 0.6), np.zeros(n)))
    poses[0, :1] += shift
    goals = np.column_stack((x, np.full(n, -0.6)))
    velocities = np.tile([0.0, -0.2], (n, 1))
    links = np.array([(i, i + 1) for i in range(n - 1)], dtype=np.int64).reshape(-1, 2)
    cells = [np.array([[xi - 0.1, 0.4], [xi + 0.1, 0.4], [xi + 0.1, 0.8], [xi - 0.1, 0.8]]) for xi in poses[0]]
    fields = dict(
        step=step,
        arena=ROBOTARIUM,
        poses=poses,
        goals=goals,
        velocities=velocities,
        links=links,
        obstacles=[OBSTACLE],
        cells=cells,
        title="collisions 0",
    )
    fields.update(overrides)
    return Frame(**fields)


def pixel(renderer: Renderer, image: np.ndarray, x: float, y: float) -> np.ndarray:
    """The RGB pixel of ``image`` at world point ``(x, y)``."""
    px, py = renderer.axes.transData.transform((x, y))
    return image[image.shape[0] - 1 - int(py), int(px)].astype(int)


def drawn_near(renderer: Renderer, image: np.ndarray, x: float, y: float) -> bool:
    """Whether anything non-white is within a pixel of world point ``(x, y)`` (thin lines)."""
    px, py = renderer.axes.transData.transform((x, y))
    row, col = image.shape[0] - 1 - int(py), int(px)
    return bool((image[row - 1 : row + 2, col - 1 : col + 2] < 250).any())


def rgb(colour: np.ndarray) -> np.ndarray:
    return np.round(np.asarray(colour)[:3] * 255).astype(int)


def nearest_robot(value: np.ndarray, colours: np.ndarray) -> int:
    return int(np.argmin([np.abs(value - rgb(c)).sum() for c in colours]))


def test_renderer_draws_every_overlay():
    renderer = Renderer(ROBOTARIUM)
    frame = make_frame(n=4, step=7)
    renderer.draw(frame)
    image = renderer.to_rgb()
    assert image.shape == (800, 1280, 3) and image.dtype == np.uint8
    colours = robot_colours(4)
    for i in range(4):  # robot bodies in their colours
        assert np.abs(pixel(renderer, image, frame.poses[0, i] - 0.03, 0.6 + 0.03) - rgb(colours[i])).max() <= 2
    assert np.abs(pixel(renderer, image, 0.0, 0.0) - 64).max() <= 2  # obstacle: dark grey
    assert drawn_near(renderer, image, -1.2, -0.6)  # a goal cross
    assert drawn_near(renderer, image, -1.2, 0.6 - 0.15)  # the velocity segment below robot 0
    assert drawn_near(renderer, image, 0.0, 0.6)  # the radio link between robots 1 and 2
    assert drawn_near(renderer, image, 0.4 + 0.1, 0.5)  # the cell of robot 2
    assert not drawn_near(renderer, image, 0.8, -0.6)  # nothing between the goals
    assert (pixel(renderer, image, 0.0, 0.0 + 0.5) == 255).all()  # between drawn things: white
    assert renderer.axes.get_title() == "step 7  |  collisions 0"
    assert renderer.figure is renderer.axes.figure


def test_renderer_draws_no_velocity_arrow_for_a_crashed_robot():
    renderer = Renderer(ROBOTARIUM)
    renderer.draw(make_frame(n=4, status=np.array(["ok", "crashed", "stuck", "ok"])))
    starts = [path.vertices[:, 0].mean() for path in renderer._velocities.get_paths()]  # arrows point down
    assert np.allclose(starts, [-1.2, 0.4, 1.2], atol=0.05)  # robot 1, at x = -0.4, has none
    colours = robot_colours(4)
    assert np.allclose(renderer._velocities.get_facecolor(), colours[[0, 2, 3]])
    renderer.draw(make_frame(n=4, status=np.full(4, "crashed")))
    assert not renderer._velocities.get_paths()
    assert not any(label.startswith("velocity") for label in renderer.legend_labels)


class Walk(Experiment):
    """Robots that drive forward and measure how far they went (its frame: the default one)."""

    name = "walk"
    default_n = 2

    def build(self, n):
        pass

    def after_step(self, step, poses):
        self.dxu[0] = 0.1

    def done(self, step, poses):
        return step >= 3

    def measures(self):
        return {"mean_x": float(self.sim.poses[0].mean()), "moved": True}


def test_the_default_title_has_the_name_and_measures_so_far():
    frames = []
    dream.run(Walk, backend="fast", record=frames.append)
    measured = dream.run(Walk, backend="fast").measures["mean_x"]
    assert frames[-1].title == f"walk: mean_x {measured:.3g}, moved True"
    renderer = Renderer(ROBOTARIUM)
    renderer.draw(frames[-1])
    assert (
        renderer.axes.get_title() == f"step 3, t = {frames[-1].time:.2f} s  |  walk: mean_x {measured:.3g}, moved True"
    )


def test_measures_title_is_compact_and_short():
    assert measures_title("walk", {}) == "walk"
    assert measures_title("walk", {"cost": 1234567.0, "n": 123456, "d": {"min": np.float32(0.5)}}) == (
        "walk: cost 1.23e+06, n 123456, d.min 0.5"
    )
    long = measures_title("walk", {f"measure_{i}": i / 7 for i in range(20)})
    assert len(long) == TITLE_LENGTH and long.endswith("…")


def test_renderer_image_changes_only_where_a_robot_moves():
    renderer = Renderer(ROBOTARIUM)
    renderer.draw(make_frame(n=4))
    before = renderer.to_rgb()
    renderer.draw(make_frame(n=4, shift=0.4))
    after = renderer.to_rgb()
    colour = rgb(robot_colours(4)[0])
    assert np.abs(pixel(renderer, before, -1.2 - 0.03, 0.63) - colour).max() <= 2
    assert (pixel(renderer, after, -1.2 - 0.03, 0.63) == 255).all()  # robot 0 left: white
    assert np.abs(pixel(renderer, after, -0.8 - 0.03, 0.63) - colour).max() <= 2  # ... and is here
    x3 = 1.2  # robot 3 did not move
    assert (pixel(renderer, before, x3 - 0.03, 0.63) == pixel(renderer, after, x3 - 0.03, 0.63)).all()
    assert (before != after).any(axis=2).sum() < 0.05 * before.shape[0] * before.shape[1]


def test_renderer_redraws_what_is_added_to_its_axes():
    renderer = Renderer(ROBOTARIUM)
    renderer.draw(make_frame())
    first = renderer.to_rgb()
    from matplotlib.patches import Circle

    renderer.axes.add_patch(Circle((0.0, -0.8), 0.1, color="red"))  # as seed-style scripts do
    renderer.draw(make_frame())
    assert (pixel(renderer, first, 0.0, -0.8) == 255).all()
    assert (pixel(renderer, renderer.to_rgb(), 0.0, -0.8) == (255, 0, 0)).all()


def test_robot_colours_cycle():
    tab10 = robot_colours(10)
    assert len({tuple(c) for c in tab10}) == 10
    many = robot_colours(45)
    assert len({tuple(c) for c in many}) == 20
    np.testing.assert_array_equal(many[0], many[20])
    np.testing.assert_array_equal(many[5], many[45 - 20 - 20])
    assert not np.array_equal(many[0], many[1])


def test_renderer_colours_robots_in_cycle():
    n = 25
    renderer = Renderer(ROBOTARIUM)
    frame = make_frame(n=n, cells=[], velocities=None, links=None)
    frame.poses[1] = np.repeat([0.6, 0.0, -0.6, -0.3, 0.3], 5)  # five rows of five
    frame.poses[0] = np.tile(np.linspace(-1.2, 1.2, 5), 5)
    renderer.draw(frame)
    image = renderer.to_rgb()
    colours = robot_colours(n)
    seen = [pixel(renderer, image, frame.poses[0, i] - 0.03, frame.poses[1, i] + 0.03) for i in range(n)]
    assert [nearest_robot(s, colours[:20]) for s in seen] == [i % 20 for i in range(n)]


def test_renderer_skips_nan_goals_and_keeps_goal_colours():
    renderer = Renderer(ROBOTARIUM)
    goals = np.array([[-1.0, -0.6], [np.nan, np.nan], [1.0, -0.6]])
    renderer.draw(make_frame(n=3, goals=goals, velocities=None, links=None, cells=[]))
    image = renderer.to_rgb()
    colours = robot_colours(3)
    assert nearest_robot(pixel(renderer, image, -1.0, -0.6), colours) == 0
    assert nearest_robot(pixel(renderer, image, 1.0, -0.6), colours) == 2  # not robot 1's colour
    assert (pixel(renderer, image, 0.0, -0.6) == 255).all()  # robot 1's goal would be under x = 0


def test_renderer_draws_an_empty_swarm_and_a_new_arena():
    renderer = Renderer(ROBOTARIUM)
    renderer.draw(make_frame(n=0, obstacles=[], cells=[]))
    assert renderer.to_rgb().shape == (800, 1280, 3)
    big = ArenaSpec.centred(6.4, 4.0)
    renderer.draw(make_frame(n=4, arena=big, poses=np.array([[-3.0, 3.0, 0.0, 0.0], [-1.8, 1.8, 0, 0], [0, 0, 0, 0]])))
    renderer.to_rgb()
    xmin, xmax = renderer.axes.get_xlim()
    assert xmin < -3.2 and xmax > 3.2 and renderer.following == "arena"


def images(count: int, size: tuple[int, int] = (64, 48)) -> list[np.ndarray]:
    """Distinct images of a few flat colours (a square that moves)."""
    width, height = size
    out = []
    for k in range(count):
        image = np.full((height, width, 3), 255, dtype=np.uint8)
        image[10:20, 2 * k : 2 * k + 10] = (31, 119, 180)
        image[30:40, 5:15] = (k * 20 % 256, 0, 0)
        out.append(image)
    return out


def test_video_writer_gif_has_every_frame(tmp_path):
    path = tmp_path / "run.gif"
    frames = images(7)
    frames.insert(3, frames[2].copy())  # an unchanged frame is still a frame
    with VideoWriter(path, fps=20) as writer:
        for image in frames:
            writer.add(image)
    assert writer.frames_written == 8
    with Image.open(path) as gif:
        assert gif.n_frames == 8 and gif.size == (64, 48)
        assert gif.info["loop"] == 0 and gif.info["duration"] == 50
        for k, want in enumerate(frames):
            gif.seek(k)
            np.testing.assert_array_equal(np.asarray(gif.convert("RGB")), want)


def test_video_writer_mp4_has_every_frame_padded_to_even_size(tmp_path):
    path = tmp_path / "run.mp4"
    with VideoWriter(path, fps=10) as writer:
        for image in images(9, size=(65, 47)):
            writer.add(image)
    assert writer.frames_written == 9
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(path))
    assert frames == 9 and seconds == pytest.approx(0.9, abs=0.05)
    reader = imageio_ffmpeg.read_frames(str(path))
    assert next(reader)["size"] == (66, 48)
    assert sum(1 for _ in reader) == 9
    reader.close()


@pytest.mark.parametrize("name", ["run.avi", "run", "run.GIF.png"])
def test_video_writer_rejects_unknown_suffix(tmp_path, name):
    with pytest.raises(ValueError, match=r"supported: \.gif, \.mp4"):
        VideoWriter(tmp_path / name)
    assert not (tmp_path / name).exists()


def test_video_writer_rejects_missing_directory_and_other_sizes(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        VideoWriter(tmp_path / "nowhere" / "run.gif")
    writer = VideoWriter(tmp_path / "run.gif")
    writer.add(images(1)[0])
    with pytest.raises(ValueError, match="64x48"):
        writer.add(images(1, size=(32, 32))[0])
    with pytest.raises(ValueError, match=r"\(H, W, 3\) or \(H, W, 4\) uint8"):
        writer.add(np.zeros((48, 64, 3)))
    writer.close()
    assert Image.open(tmp_path / "run.gif").n_frames == 1


def test_video_writer_without_frames_writes_nothing(tmp_path):
    VideoWriter(tmp_path / "run.mp4").close()
    VideoWriter(tmp_path / "run.gif").close()
    assert list(tmp_path.iterdir()) == []


def test_recorder_renders_every_kth_frame_from_the_first(tmp_path, monkeypatch):
    drawn = []
    original = Renderer.draw

    def spy(self, frame):
        drawn.append(frame.step)
        original(self, frame)

    monkeypatch.setattr(Renderer, "draw", spy)
    path = tmp_path / "run.gif"
    with Recorder(video=path, every=3) as recorder:
        assert recorder.renderer is None  # made from the first frame's arena
        for step in range(10):
            recorder(make_frame(step=step, shift=0.05 * step))
    assert drawn == [0, 3, 6, 9]
    assert recorder.frames_rendered == 4 and recorder.frames_seen == 10
    assert recorder.writer.frames_written == 4
    assert Image.open(path).n_frames == 4


def test_recorder_takes_its_arena_from_the_first_frame():
    big = ArenaSpec.centred(10.0, 6.0)
    recorder = Recorder()
    recorder(make_frame(arena=big))
    assert recorder.renderer.arena == big and recorder.renderer.following == "swarm"  # a row 2.4 m long
    assert recorder.frames_rendered == 1 and recorder.video is None


@pytest.mark.parametrize("every", [0, -1, 1.5, True])
def test_recorder_rejects_bad_every(every):
    with pytest.raises(ValueError, match="every"):
        Recorder(every=every)


def test_recorder_from_args_makes_what_the_options_ask_for(tmp_path):
    parser = argparse.ArgumentParser()
    Recorder.add_arguments(parser)
    assert Recorder.from_args(parser.parse_args([])) is None  # no drawing asked for: nothing to draw
    path = tmp_path / "run.gif"
    recorder = Recorder.from_args(parser.parse_args(["--video", str(path), "--every", "2"]))
    assert recorder.video == path and recorder.every == 2 and not recorder.show and not recorder.keep_open
    shown = Recorder.from_args(argparse.Namespace(video=None, show=True))  # --every is optional
    assert shown.video is None and shown.show and shown.keep_open and shown.every == 1


@pytest.mark.parametrize(
    ("options", "message"), [(["--video", "run.avi"], "suffix"), (["--show", "--every", "0"], "every")]
)
def test_recorder_from_args_refuses_bad_options(capsys, options, message):
    parser = argparse.ArgumentParser()
    Recorder.add_arguments(parser)
    args = parser.parse_args(options)
    with pytest.raises(ValueError, match=message):
        Recorder.from_args(args)
    with pytest.raises(SystemExit) as exit_info:  # through the parser: one line, exit code 2
        Recorder.from_args(args, parser)
    assert exit_info.value.code == 2 and message in capsys.readouterr().err


def test_recorder_show_without_display_warns_and_still_records(tmp_path):
    import matplotlib.pyplot as plt

    plt.switch_backend("Agg")
    path = tmp_path / "run.mp4"
    try:
        with pytest.warns(RuntimeWarning, match="not interactive"), Recorder(video=path, show=True) as recorder:
            for step in range(4):
                recorder(make_frame(step=step, shift=0.1 * step))
        assert plt.fignum_exists(recorder.renderer.figure.number)  # a pyplot figure
        assert not recorder.live
        recorder.hold()  # returns at once without a window
        assert recorder.frames_rendered == 4
        assert imageio_ffmpeg.count_frames_and_secs(str(path))[0] == 4
    finally:
        plt.close("all")


def test_importing_viz_imports_no_matplotlib():
    code = "import sys, dream.viz; sys.exit('matplotlib' in sys.modules)"
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MPLBACKEND")}
    assert subprocess.run([sys.executable, "-c", code], env=env, check=False).returncode == 0
