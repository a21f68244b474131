"""What the pictures show (legend, roles, faults, heading, ranges, the followed view), the live
window's life cycle (mocked, headless), real-time pacing (a fake clock), and the CLI's options."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from dream import Faults, viz
from dream.cli import _parser, main
from dream.experiments import EXPERIMENTS, Experiment, run
from dream.frames import Frame, fault_status
from dream.specs import ROBOTARIUM, ArenaSpec
from dream.viz import Recorder, Renderer, VideoWriter, robot_colours, video

R = viz.ROBOT_DIAMETER / 2


def row(n: int = 4, y: float = 0.0, heading: float = 0.0, **fields) -> Frame:
    """``n`` robots on a row at height ``y`` in the Robotarium, all facing ``heading``."""
    x = np.linspace(-1.2, 1.2, n)
    poses = np.vstack((x, np.full(n, y), np.full(n, heading)))
    return Frame(**{"step": 3, "arena": ROBOTARIUM, "poses": poses, **fields})


def pixel(renderer: Renderer, image: np.ndarray, x: float, y: float) -> np.ndarray:
    px, py = renderer.axes.transData.transform((x, y))
    return image[image.shape[0] - 1 - int(py), int(px)].astype(int)


def close_to(value: np.ndarray, colour, tolerance: int = 12) -> bool:
    from matplotlib.colors import to_rgba

    return bool(np.abs(value - np.round(np.asarray(to_rgba(colour))[:3] * 255)).max() <= tolerance)


def drawn(renderer: Renderer, frame: Frame) -> np.ndarray:
    renderer.draw(frame)
    return renderer.to_rgb()


def test_pictures_are_1280x800_by_default_and_take_a_size():
    assert drawn(Renderer(ROBOTARIUM), row()).shape == (800, 1280, 3)
    assert drawn(Renderer(ROBOTARIUM, size=(640, 400)), row()).shape == (400, 640, 3)
    assert drawn(Renderer(ROBOTARIUM, size=(1001, 333)), row()).shape == (333, 1001, 3)


def test_legend_lists_what_the_frame_shows_and_is_drawn():
    renderer = Renderer(ROBOTARIUM)
    image = drawn(renderer, row(velocities=np.tile([0.0, 0.1], (4, 1)), links=np.array([[0, 1]])))
    assert renderer.legend_labels == [
        "robot (to scale; notch: heading)",
        "velocity (arrow: the way in 1 s)",
        "radio link",
    ]
    legend = image[:, int(0.77 * 1280) :]  # the column right of the axes
    assert (legend < 200).any(axis=2).sum() > 500  # text and handles
    box = np.array([[-0.1, -0.5], [0.1, -0.5], [0.1, -0.3], [-0.1, -0.3]])
    drawn(renderer, row(obstacles=[box, box + [0.5, 0]], obstacle_moving=[False, True]))
    assert renderer.legend_labels == ["robot (to scale; notch: heading)", "static obstacle", "moving obstacle"]


def test_static_and_moving_obstacles_look_different():
    renderer = Renderer(ROBOTARIUM)
    box = np.array([[-0.2, -0.8], [0.2, -0.8], [0.2, -0.4], [-0.2, -0.4]])
    image = drawn(renderer, row(obstacles=[box, box + [0.8, 0]], obstacle_moving=[False, True]))
    assert close_to(pixel(renderer, image, 0.0, -0.6), viz.OBSTACLE_COLOUR, 2)
    patch = [pixel(renderer, image, 0.8 + dx, -0.6 + dy) for dx in (-0.1, 0, 0.1) for dy in (-0.1, 0, 0.1)]
    assert any(close_to(p, viz.MOVING_OBSTACLE_COLOUR) for p in patch)  # brown between the hatches
    assert not any(close_to(p, viz.OBSTACLE_COLOUR, 2) for p in patch)


def test_heading_notch_turns_with_the_robot():
    for heading, ahead, behind in (
        (0.0, (0.7 * R, 0.0), (-0.7 * R, 0.0)),
        (np.pi / 2, (0.0, 0.7 * R), (0.0, -0.7 * R)),
    ):
        renderer = Renderer(ROBOTARIUM)
        image = drawn(renderer, row(n=1, heading=heading, poses=np.array([[0.0], [0.0], [heading]])))
        assert pixel(renderer, image, *ahead).max() < 60  # the dark notch at the front
        assert close_to(pixel(renderer, image, *behind), robot_colours(1)[0], 3)  # body colour behind


def test_velocity_is_an_arrow_with_a_head():
    renderer = Renderer(ROBOTARIUM)
    image = drawn(renderer, row(n=1, poses=np.array([[0.0], [0.0], [0.0]]), velocities=np.array([[0.0, 0.3]])))
    colour = robot_colours(1)[0]
    assert close_to(pixel(renderer, image, 0.0, 0.2), colour)  # shaft, outside the body
    assert close_to(pixel(renderer, image, 0.008, 0.27), colour)  # head: wider than the shaft
    assert (pixel(renderer, image, 0.014, 0.2) > 240).all()  # beside the shaft: white
    assert (pixel(renderer, image, 0.0, 0.32) > 240).all()  # past the tip


def test_roles_and_faults_are_marked():
    renderer = Renderer(ROBOTARIUM)
    roles = np.array(["leader", "follower", "follower", "follower"])
    status = np.array(["ok", "crashed", "stuck", "byzantine"])
    frame = row(roles=roles, status=status)
    image = drawn(renderer, frame)
    x = frame.poses[0]
    assert (pixel(renderer, image, x[0], 0.0) > 240).all()  # the leader's white star at its centre
    assert close_to(pixel(renderer, image, x[2] - 0.03, 0.0), robot_colours(4)[2], 3)  # followers plain
    assert close_to(pixel(renderer, image, x[1] - 0.03, 0.02), viz.CRASHED_COLOUR, 3)  # grey ...
    assert pixel(renderer, image, x[1] - 0.7 * R * 0.7, 0.7 * R * 0.7).max() < 80  # ... with a cross
    assert close_to(pixel(renderer, image, x[2] - 0.7 * viz.ROBOT_DIAMETER, 0.0), viz.STUCK_COLOUR, 40)
    assert close_to(pixel(renderer, image, x[3] - 0.8 * viz.ROBOT_DIAMETER, 0.0), viz.BYZANTINE_COLOUR, 40)
    labels = renderer.legend_labels
    for want in ("crashed (grey, cross)", "stuck (wheels stopped)", "Byzantine (lies)", "follower (plain)", "leader"):
        assert want in labels


def test_title_has_step_time_and_measures():
    renderer = Renderer(ROBOTARIUM)
    image = drawn(renderer, row(time=0.099, title="coverage cost 0.42"))
    assert renderer.axes.get_title() == "step 3, t = 0.10 s  |  coverage cost 0.42"
    strip = image[: int(800 * 0.07)]
    assert (strip < 100).any()  # painted above the axes
    renderer.draw(row(time=1.5, title="coverage cost 0.40"))
    assert not np.array_equal(renderer.to_rgb()[: int(800 * 0.07)], strip)


def test_view_follows_a_small_swarm_in_a_large_arena_and_keeps_the_aspect():
    arena = ArenaSpec.centred(40.0, 25.0)
    rng = np.random.default_rng(0)
    xy = rng.uniform([9.0, 4.0], [11.0, 5.0], size=(20, 2)).T
    renderer = Renderer(arena)
    renderer.draw(Frame(0, arena, np.vstack((xy, np.zeros(20)))))
    (xmin, xmax), (ymin, ymax) = renderer.axes.get_xlim(), renderer.axes.get_ylim()
    assert renderer.following == "swarm"
    assert xmin <= xy[0].min() - 0.3 and xy[0].max() + 0.3 <= xmax and ymin <= xy[1].min() and xy[1].max() <= ymax
    assert xmax - xmin < 5.0  # not the 40 m arena
    width, height = renderer.figure.bbox.width * viz.AXES_RECT[2], renderer.figure.bbox.height * viz.AXES_RECT[3]
    assert (xmax - xmin) / (ymax - ymin) == pytest.approx(width / height)
    assert renderer.robot_pixels() > 20
    before = renderer.view
    renderer.draw(Frame(1, arena, np.vstack((xy + 0.05, np.zeros(20)))))  # a small move: the view stays
    assert renderer.view == before
    renderer.draw(Frame(2, arena, np.vstack((xy - 8.0, np.zeros(20)))))  # the swarm left: the view follows
    assert renderer.axes.get_xlim()[1] < xy[0].min() - 5.0


def test_view_shows_the_whole_arena_when_the_swarm_fills_it():
    arena = ArenaSpec.centred(4.0, 2.5)
    renderer = Renderer(arena)
    renderer.draw(Frame(0, arena, np.array([[-1.9, 1.9, 0.0], [-1.2, 1.2, 0.0], [0.0, 0.0, 0.0]])))
    assert renderer.following == "arena"
    (xmin, xmax), (ymin, ymax) = renderer.axes.get_xlim(), renderer.axes.get_ylim()
    assert xmin < -2.0 and xmax > 2.0 and ymin < -1.25 and ymax > 1.25


def test_view_zooms_on_the_focus_robot_when_robots_would_be_specks():
    arena = ArenaSpec.centred(60.0, 40.0)
    rng = np.random.default_rng(1)
    poses = np.vstack((rng.uniform(-29, 29, (2, 500)), np.zeros(500)))
    whole = Renderer(arena)
    whole.draw(Frame(0, arena, poses))
    assert whole.following == "arena" and whole.robot_pixels() < viz.MIN_ROBOT_PIXELS
    focused = Renderer(arena, focus=7)
    focused.draw(Frame(0, arena, poses, ranges={"sensing": 1.0}))
    (xmin, xmax), (ymin, ymax) = focused.axes.get_xlim(), focused.axes.get_ylim()
    assert focused.following == "focus" and focused.robot_pixels() > 10
    assert xmin < poses[0, 7] - 1.0 and poses[0, 7] + 1.0 < xmax and ymin < poses[1, 7] - 1.0 < poses[1, 7] + 1.0 < ymax
    assert "view: follows robot 7 (too many to show all)" in focused.legend_labels


def test_focus_draws_ranges_and_lines_to_the_robots_it_hears():
    renderer = Renderer(ROBOTARIUM, focus=1)
    frame = row(n=4, links=np.array([[0, 1], [1, 3], [2, 3]]), ranges={"sensing": 0.6, "radio": 0.9})
    image = drawn(renderer, frame)
    x = frame.poses[0, 1]
    assert close_to(pixel(renderer, image, x, 0.6), viz.RANGE_COLOURS[0], 60) or close_to(
        pixel(renderer, image, x, 0.6 - 0.004), viz.RANGE_COLOURS[0], 60
    )
    heard = {tuple(np.round(segment[1], 6)) for segment in renderer._heard.get_segments()}
    assert heard == {(frame.poses[0, 0], 0.0), (frame.poses[0, 3], 0.0)}  # its links, not robot 2
    assert renderer.legend_labels[-4:] == [
        "robot 1 (focus)",
        "sensing 0.6 m",
        "radio 0.9 m",
        "heard by robot 1 (links)",
    ]


def test_focus_without_ranges_draws_a_default_metre_and_says_so():
    renderer = Renderer(ROBOTARIUM, focus=0)
    frame = row(n=4)  # robots 0.8 m apart: robot 1 is within 1 m of robot 0, the others are not
    image = drawn(renderer, frame)
    assert renderer._ranges.get_offsets().shape == (1, 2)
    assert "range 1 m (default: none given)" in renderer.legend_labels
    assert "heard by robot 0 (in range)" in renderer.legend_labels
    assert len(renderer._heard.get_segments()) == 1
    assert (pixel(renderer, image, frame.poses[0, 0] + 1.0, 0.0) < 250).any() or (
        pixel(renderer, image, frame.poses[0, 0] + 0.996, 0.0) < 250
    ).any()


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"roles": np.array(["a", "b"])}, r"frame.roles has 2 labels, expected 4"),
        ({"status": np.array(["ok", "ok", "ok", "asleep"])}, r"frame.status has \['asleep'\]"),
        ({"obstacles": [np.zeros((4, 2))], "obstacle_moving": [True, False]}, "frame.obstacle_moving has 2"),
        ({"ranges": {"radio": -1.0}}, r"frame.ranges\['radio'\] must be a distance > 0"),
    ],
)
def test_renderer_rejects_frames_with_bad_fields(fields, match):
    with pytest.raises(ValueError, match=match):
        Renderer(ROBOTARIUM).draw(row(**fields))


def test_renderer_rejects_bad_size_and_focus():
    for size in ((10, 10), (640.5, 400), "640x400", (640,)):
        with pytest.raises(ValueError, match="size must be"):
            Renderer(ROBOTARIUM, size=size)
    with pytest.raises(ValueError, match="focus must be a robot id"):
        Renderer(ROBOTARIUM, focus=-1)
    with pytest.raises(ValueError, match=r"focus=9: the frame has 4 robots \(ids 0..3\)"):
        Renderer(ROBOTARIUM, focus=9).draw(row())
    assert viz.parse_size(" 800X600 ") == (800, 600)
    for text in ("800", "800x", "ax600", "10x10"):
        with pytest.raises(ValueError, match="size must be"):
            viz.parse_size(text)


def test_fault_status_shows_the_worst_fault():
    crashed = np.array([True, False, False, False, True])
    stuck = np.array([True, True, False, False, False])
    byzantine = np.array([False, True, True, False, True])
    assert fault_status(crashed, stuck, byzantine).tolist() == ["crashed", "stuck", "byzantine", "ok", "crashed"]


def test_video_writer_takes_rgba_without_a_copy_and_keeps_one_kind(tmp_path):
    path = tmp_path / "run.gif"
    rgba = np.full((48, 64, 4), 255, dtype=np.uint8)
    rgba[10:20, 10:20, :3] = (200, 30, 30)
    with VideoWriter(path) as writer:
        writer.add(rgba)
        with pytest.raises(ValueError, match="3 channels, but this video's frames have 4"):
            writer.add(rgba[..., :3])
    with Image.open(path) as gif:
        np.testing.assert_array_equal(np.asarray(gif.convert("RGB")), rgba[..., :3])


# -- the live window, headless: an Agg pyplot figure that the recorder takes for a window ---------


@pytest.fixture
def window(monkeypatch):
    import matplotlib.pyplot as plt

    plt.switch_backend("Agg")
    monkeypatch.setattr("dream.viz.recorder._interactive", lambda canvas: True)
    calls: list[str] = []
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    monkeypatch.setattr(FigureCanvasAgg, "blit", lambda self, bbox=None: calls.append("blit"), raising=False)
    monkeypatch.setattr(FigureCanvasAgg, "flush_events", lambda self: calls.append("flush"), raising=False)
    monkeypatch.setattr(plt, "show", lambda block=None: calls.append(f"show block={block}"))
    yield calls
    plt.close("all")


def test_live_window_is_blitted_every_frame_and_closes_at_the_end(window):
    import matplotlib.pyplot as plt

    with Recorder(show=True) as recorder:
        for step in range(3):
            recorder(row(step=step))
        assert recorder.live and plt.fignum_exists(recorder.renderer.figure.number)
    assert window.count("blit") == 6 and window.count("flush") >= 3
    assert window[0] == "show block=False"  # the window opens before the first frame
    assert not recorder.live and not plt.fignum_exists(recorder.renderer.figure.number)
    recorder.hold()  # no window: returns at once
    assert "show block=True" not in window


def test_live_window_with_hold_stays_open_until_the_user_closes_it(window):
    import matplotlib.pyplot as plt

    with Recorder(show=True, hold=True) as recorder:
        recorder(row())
    assert plt.fignum_exists(recorder.renderer.figure.number)
    recorder.hold()
    assert window[-1] == "show block=True"
    assert not recorder.renderer.axes.title.get_animated()  # a repaint of the held window shows the frame


def test_window_closed_by_the_user_stops_the_live_view_not_the_video(window, tmp_path):
    import matplotlib.pyplot as plt

    with Recorder(show=True, video=tmp_path / "run.gif") as recorder:
        recorder(row(step=0))
        plt.close(recorder.renderer.figure)
        recorder(row(step=1))
    assert window.count("blit") == 2 and recorder.writer.frames_written == 2


def test_realtime_paces_rendered_frames_to_simulated_time():
    recorder = Recorder(realtime=True, every=2)
    now = [100.0]
    sleeps: list[float] = []
    recorder._clock = lambda: now[0]

    def sleep(seconds: float) -> None:
        sleeps.append(seconds)
        now[0] += seconds

    recorder._sleep = sleep
    for step in range(7):
        now[0] += 0.01  # drawing is faster than the simulated 0.033 s a step
        recorder(row(step=step, time=step * 0.033))
    # rendered: steps 0, 2, 4, 6; each waits until 0.066 s of wall time after the one before
    assert len(sleeps) == 3 and sum(sleeps) == pytest.approx(3 * (2 * 0.033 - 2 * 0.01))
    assert recorder.waited == pytest.approx(sum(sleeps))
    late = Recorder(realtime=True)
    late._clock, late._sleep = (lambda: now[0]), sleep
    for step in range(3):
        now[0] += 1.0  # slower than real time: never waits
        late(row(step=step, time=step * 0.033))
    assert late.waited == 0.0


# -- the runner fills the time and the fault status --------------------------------------------------


class Still(Experiment):
    """Robots that do not move."""

    name = "still"
    default_n = 6

    def build(self, n):
        pass

    def steps(self, n):
        return 4


def test_runner_fills_time_and_fault_status():
    frames: list[Frame] = []
    result = run(Still, record=frames.append, backend="fast", faults=Faults(crash=0.5, crash_at=2, byzantine=1))
    assert [f.time for f in frames] == pytest.approx([0.033 * k for k in range(1, 5)])
    expected = np.full(6, "ok", dtype=object)
    for event in result.faults["events"]:
        if expected[event["robot"]] != "crashed":  # a crashed liar shows as crashed, the worst
            expected[event["robot"]] = "crashed" if event["kind"] == "crash" else "byzantine"
    assert frames[-1].status.tolist() == expected.tolist()
    assert frames[0].status.tolist().count("crashed") == 0  # the crash comes at step 2


# -- the CLI's options -----------------------------------------------------------------------------


def test_cli_parses_size_focus_realtime_hold():
    args = _parser().parse_args(["run", "x", "--size", "640x400", "--focus", "3", "--realtime", "--hold"])
    assert (args.size, args.focus, args.realtime, args.hold) == ((640, 400), 3, True, True)
    args = _parser().parse_args(["run", "x"])
    assert (args.size, args.focus, args.realtime, args.hold) == ((1280, 800), None, False, False)


@pytest.mark.parametrize(("option", "value"), [("--size", "big"), ("--size", "20x20"), ("--focus", "-1")])
def test_cli_rejects_bad_size_and_focus(capsys, option, value):
    with pytest.raises(SystemExit) as exited:
        main(["run", "hrvo-circle", "--video", "out.gif", option, value])
    assert exited.value.code == 2
    assert f"argument {option}:" in capsys.readouterr().err


def test_cli_refuses_a_focus_robot_the_run_does_not_have(monkeypatch, capsys, tmp_path):
    ran = []
    monkeypatch.setitem(EXPERIMENTS, "still", type("S", (Still,), {"build": lambda self, n: ran.append(n)}))
    path = tmp_path / "out.gif"
    assert main(["run", "still", "--video", str(path), "--focus", "6"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == "dream: error: --focus 6: no such robot; the run has 6 (ids 0 to 5)"
    assert ran == [] and not path.exists()


def test_cli_passes_drawing_options_to_the_recorder(monkeypatch, tmp_path, capsys):
    made = {}

    class Spy(Recorder):
        def __init__(self, **kwargs):
            made.update(kwargs)
            super().__init__(**kwargs)

    monkeypatch.setattr(viz, "Recorder", Spy)
    monkeypatch.setitem(EXPERIMENTS, "still", Still)
    path = tmp_path / "out.gif"
    argv = ["run", "still", "--backend", "fast", "--video", str(path), "--size", "320x200", "--focus", "2"]
    assert main([*argv, "--realtime", "--no-progress"]) == 0
    assert (made["size"], made["focus"], made["realtime"], made["hold"]) == ((320, 200), 2, True, False)
    assert Image.open(path).size == (320, 200)


def test_a_signal_during_a_frame_write_waits_until_the_frame_is_written():
    import os
    import signal

    steps = []
    # Python's own handler, whatever the process inherited: a job started in the background
    # (`cmd &` in a script) ignores SIGINT, and the signal would then never arrive.
    inherited = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt), video._signals_deferred():
            os.kill(os.getpid(), signal.SIGINT)
            steps.append("after the signal")  # the block goes on
        assert steps == ["after the signal"]
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored
    finally:
        signal.signal(signal.SIGINT, inherited)
