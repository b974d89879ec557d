"""Tests of the scene animation (crashsim.animation and ``crashsim animate``), under Agg.

The intersection scene is the fastest shipped run-out scene (about 0.1 s to run once the
kernels are compiled); a large dt (0.5 s: 7 frames) keeps the rendering short.
"""

from __future__ import annotations

import functools
import re
import math
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
from matplotlib import animation as mpl_animation  # noqa: E402

from crashsim.animation import (HOLD, MAX_FRAMES, animate_scene, animation_formats, frame_times,  # noqa: E402
                                scene_animation)
from crashsim.cli import main  # noqa: E402
from crashsim.errors import ScenarioError  # noqa: E402
from crashsim.geometry import rotate  # noqa: E402
from crashsim.plotting import plot_scene  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402
from crashsim.units import Kind, to_unit  # noqa: E402

Image = pytest.importorskip("PIL.Image")

ROOT = Path(__file__).resolve().parents[2]
INTERSECTION = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"
WAITING = ROOT / "scenarios" / "scenes" / "third_vehicle_waiting_car.toml"  # legend at the right
TABLE6 = ROOT / "scenarios" / "paper" / "table6.toml"  # impact only
TRUCK = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"  # a long approach
DT = 0.5


@functools.lru_cache(maxsize=None)
def _scene(path: Path):
    return run_scene(load_scenario(path))


def _run_end(scene) -> float:
    return max(r.t_end for r in scene.runout.values())


def _bodies(scene):
    """(vehicle run-out, body name, Body, BodyRunout) of every body of the run-out."""
    body_of = {b.name: b for v in scene.scenario.vehicles for b in v.bodies}
    return [(r, name, body_of[name], br) for r in scene.runout.values() for name, br in r.bodies.items()]


def _corners(body, position, heading, k=1.0) -> np.ndarray:
    """Outline corners in the world, scaled by k (display units per metre)."""
    return k * (np.asarray(position, dtype=float) + rotate(body.outline(), heading))


def _vertices(patch) -> np.ndarray:
    xy = np.asarray(patch.get_xy(), dtype=float)
    return xy[:-1] if len(xy) > 4 and np.allclose(xy[0], xy[-1]) else xy


# -- frame times ----------------------------------------------------------------------------

def test_frame_times_are_multiples_of_dt_and_end_exactly_at_the_end():
    t = frame_times(2.9483, 0.5)
    np.testing.assert_allclose(t[:-1], 0.5 * np.arange(6))
    assert t[-1] == 2.9483 and len(t) == math.ceil(2.9483 / 0.5) + 1
    t = frame_times(3.0, 0.5)  # the end is a multiple: not repeated
    assert len(t) == 7 and t[-1] == 3.0 and np.all(np.diff(t) > 0)
    t = frame_times(0.3 * 3, 0.3)  # 0.9 / 0.3 is 2.9999999999999996 in floating point
    assert len(t) == 4 and t[-1] == 0.3 * 3
    np.testing.assert_array_equal(frame_times(0.0, 0.05), [0.0])


@pytest.mark.parametrize("dt", [0.0, -0.1, float("nan"), float("inf")])
def test_frame_times_refuse_a_non_positive_dt(dt):
    with pytest.raises(ScenarioError, match=r"^dt: .*not a positive time.*allowed dt >= 0.0015 s"):
        frame_times(3.0, dt)
    with pytest.raises(ScenarioError) as exc:  # before the run-out's end is known: no "dt >= 0 s"
        frame_times(0.0, dt)
    assert str(exc.value).endswith('allowed a time > 0 s, e.g. "0.05 s"') and ">= 0 s" not in str(exc.value)


def test_frame_times_refuse_too_many_frames_and_state_the_smallest_dt():
    assert len(frame_times(3.0, 3.0 / (MAX_FRAMES - 1))) == MAX_FRAMES
    with pytest.raises(ScenarioError, match=rf"--dt: .*gives {3001} frames.*>= 0.0015 s \(at most {MAX_FRAMES}"):
        frame_times(3.0, 0.001, field="--dt")


# -- frames ---------------------------------------------------------------------------------

def test_number_of_frames_and_clock():
    scene = _scene(INTERSECTION)
    anim = scene_animation(scene, dt=DT)
    t_end = _run_end(scene)
    assert len(anim) == math.ceil(t_end / DT) + 1 == 7
    assert anim.times[0] == 0.0 and anim.times[-1] == t_end
    anim.frame(1)
    assert anim.clock.get_text() == "t = 0.5 s"
    anim.frame(len(anim) - 1)
    assert anim.clock.get_text() == f"t = {t_end:.1f} s, at rest"
    assert scene_animation(scene, dt=0.05).clock_text(25) == "t = 1.25 s"


def test_outline_of_frame_k_is_the_body_at_sol_of_t_k_clamped_to_its_run():
    scene = _scene(INTERSECTION)
    anim = scene_animation(scene, dt=DT)
    ends = {r.t_end for r in scene.runout.values()}
    assert len(ends) == 2, "the car stops before the truck: its clamp is exercised"
    bodies = _bodies(scene)
    for k, t in enumerate(anim.times):
        anim.frame(k)
        for r, name, body, br in bodies:
            x, y, heading = np.asarray(br.sol(min(t, r.t_end)), dtype=float)[:3]
            np.testing.assert_allclose(_vertices(anim.outlines[name]), _corners(body, (x, y), heading), atol=1e-9)
        # hitch pins at the front body's pin
        for v in scene.scenario.vehicles:
            if v.hitches:
                front = scene.runout_body(v.bodies[0].name)
                tc = min(t, scene.runout[v.name].t_end)
                x, y, heading = np.asarray(front.sol(tc), dtype=float)[:3]
                pin = np.asarray((x, y)) + rotate(np.asarray(v.hitches[0].front_point), heading)
                np.testing.assert_allclose(np.column_stack(anim.pins[v.name].get_data())[0], pin, atol=1e-9)
    # the car has stopped at frame 3 (t = 1.5 s > its end): it stays at rest
    car = scene.runout_body("car")
    assert anim.times[3] > scene.runout["B"].t_end
    anim.frame(3)
    body = next(b for _, n, b, _ in bodies if n == "car")
    np.testing.assert_allclose(_vertices(anim.outlines["car"]), _corners(body, car.rest_position, car.rest_heading),
                               atol=1e-9)


def test_poses_clamp_time_to_each_run():
    """A dense output that extrapolates (x = t) is read only inside [0, t_end] of its run."""
    from types import SimpleNamespace

    from crashsim.animation import SceneAnimation

    def body(t_end):
        return SimpleNamespace(sol=lambda t: np.array([t, 2.0 * t, 0.1 * t, 1.0, 2.0, 0.1]))

    runout = {"A": SimpleNamespace(t_end=1.0, bodies={"a": body(1.0)}),
              "B": SimpleNamespace(t_end=3.0, bodies={"b1": body(3.0), "b2": body(3.0)})}
    anim = SceneAnimation(SimpleNamespace(runout=runout), None, None, np.array([0.0, 2.5]), None, {}, {}, None, 1, "")
    poses = anim.poses(2.5)
    assert poses["a"] == ((1.0, 2.0), pytest.approx(0.1))
    assert poses["b1"] == poses["b2"] == ((2.5, 5.0), pytest.approx(0.25))
    assert anim.poses(-1.0)["b1"] == ((0.0, 0.0), 0.0)
    assert anim.poses(9.0)["b2"] == ((3.0, 6.0), pytest.approx(0.3))

def test_last_frame_is_the_rest_pose_and_limits_hold_every_frame():
    scene = _scene(INTERSECTION)
    anim = scene_animation(scene, dt=DT, view="scene")
    limits = anim.ax.get_xlim(), anim.ax.get_ylim()
    anim.frame(len(anim) - 1)
    for r, name, body, br in _bodies(scene):
        np.testing.assert_allclose(_vertices(anim.outlines[name]),
                                   _corners(body, br.rest_position, br.rest_heading), atol=1e-9)
    (x0, x1), (y0, y1) = limits
    for k in range(len(anim)):
        for patch in anim.frame(k)[:len(anim.outlines)]:
            xy = _vertices(patch)
            assert np.all((xy[:, 0] >= x0) & (xy[:, 0] <= x1) & (xy[:, 1] >= y0) & (xy[:, 1] <= y1))
        assert (anim.ax.get_xlim(), anim.ax.get_ylim()) == limits


@pytest.mark.parametrize("path", [INTERSECTION, WAITING], ids=["wide", "tall"])
def test_limits_widen_to_poses_outside_the_scene_figure(monkeypatch, path):
    """No shipped scene has a pose outside the static figure's limits: shrink them to provoke it
    (in the name the animation module calls). The compact legend stays outside the axes."""
    import crashsim.animation

    original = crashsim.animation.plot_scene
    shrunk_limits = []

    def shrunk(scene, **kwargs):
        ax = original(scene, **kwargs)
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        ax.set_xlim(x0 + 0.3 * (x1 - x0), x0 + 0.6 * (x1 - x0))
        ax.set_ylim(y0 + 0.4 * (y1 - y0), y0 + 0.6 * (y1 - y0))
        shrunk_limits.append((ax.get_xlim(), ax.get_ylim()))
        return ax

    monkeypatch.setattr(crashsim.animation, "plot_scene", shrunk)
    scene = _scene(path)
    anim = scene_animation(scene, dt=DT, view="scene")
    assert len(shrunk_limits) == 1, "the animation drew its static layer with the patched plot_scene"
    (sx0, sx1), (sy0, sy1) = shrunk_limits[0]
    (x0, x1), (y0, y1) = anim.ax.get_xlim(), anim.ax.get_ylim()
    assert x0 < sx0 and x1 > sx1 and y0 < sy0 and y1 > sy1, "the limits widened on every side"
    outside = 0
    for k in range(len(anim)):
        for patch in anim.frame(k)[:len(anim.outlines)]:
            xy = _vertices(patch)
            outside += int(np.any((xy[:, 0] < sx0) | (xy[:, 0] > sx1) | (xy[:, 1] < sy0) | (xy[:, 1] > sy1)))
            assert np.all((xy[:, 0] > x0) & (xy[:, 0] < x1) & (xy[:, 1] > y0) & (xy[:, 1] < y1))
    assert outside > 0, "some poses lay outside the shrunk limits: the widening was needed"
    # laid out again: the axes box has the aspect of the new limits (equal scale, nothing cut)
    fig = anim.fig
    box = anim.ax.get_position()
    w_in, h_in = box.width * fig.get_figwidth(), box.height * fig.get_figheight()
    assert w_in / h_in == pytest.approx((x1 - x0) / (y1 - y0), rel=1e-6)
    r = fig.canvas.get_renderer()
    leg = anim.ax.get_legend().get_window_extent(r)
    axes = anim.ax.get_window_extent(r)
    # the animation's legend is the compact one outside the axes (one line per entry), inside the figure
    assert not leg.overlaps(axes)
    assert leg.x0 >= 0 and leg.y0 >= 0 and leg.x1 <= fig.bbox.x1 + 1 and leg.y1 <= fig.bbox.y1 + 1
    assert all("\n" not in t.get_text() for t in anim.ax.get_legend().get_texts())


# -- the follow view ------------------------------------------------------------------------

def _outline_box(anim, k) -> np.ndarray:
    """(x0, y0, x1, y1) of every moving outline and pin at frame k [display units]."""
    pts = []
    for a in anim.frame(k):
        if a in anim.outlines.values() and hasattr(a, "get_xy"):
            pts.append(_vertices(a))
        elif a in anim.pins.values() or a in anim.outlines.values():
            pts.append(np.column_stack(a.get_data()))
    pts = np.vstack([p for p in pts if len(p)])
    return np.concatenate([pts.min(axis=0), pts.max(axis=0)])


@pytest.mark.parametrize("path", [INTERSECTION, WAITING], ids=["wide", "tall"])
def test_follow_view_frames_every_vehicle_of_each_frame(path):
    scene = _scene(path)
    anim = scene_animation(scene, dt=0.1)
    assert anim.view == "follow" and anim.limits.shape == (len(anim), 4)
    r = anim.fig.canvas.get_renderer()
    for k in range(len(anim)):
        box = _outline_box(anim, k)
        (x0, x1), (y0, y1) = anim.ax.get_xlim(), anim.ax.get_ylim()
        np.testing.assert_allclose((x0, x1, y0, y1), anim.limits[k])
        # the vehicles and a margin of at least 3 m inside the view
        assert x0 + 3.0 <= box[0] and box[2] <= x1 - 3.0 and y0 + 3.0 <= box[1] and box[3] <= y1 - 3.0
        assert x1 - x0 >= 20.0 - 1e-9
        # equal scale: the limits have the aspect of the axes box
        ext = anim.ax.get_window_extent(r)
        assert (y1 - y0) / (x1 - x0) == pytest.approx(ext.height / ext.width, rel=1e-6)
    # the scale bar follows the view: a 1-2-2.5-5 length of at most a fifth of the width
    bar = next(a for a in anim.ax.artists if a.get_gid() == "scalebar")
    assert bar.crashsim_length <= (anim.limits[-1, 1] - anim.limits[-1, 0]) / 5.0


def test_follow_view_is_closer_than_the_scene_view():
    """The truck that brakes into a car: the scene view holds 150 ft of approach; the follow view
    keeps the 17.6 m combination well over 60 px long in a 1000 px GIF at every frame (both
    vehicles in view while they close in) and frames the impact at least 2.5 times closer."""
    scene = _scene(TRUCK)
    truck = scene.scenario.vehicles[0]
    states = scene.scenario.states
    heading = states[truck.bodies[0].name].heading
    along = np.concatenate([_corners(b, states[b.name].position, states[b.name].heading) @ rotate(np.array([1.0, 0.0]),
                                                                                                    heading)
                            for b in truck.bodies])
    combination = float(np.ptp(along))  # front of the tractor to the rear of the trailer [m]
    assert 15.0 < combination < 25.0
    length_px = {}
    for view in ("scene", "follow"):
        anim = scene_animation(scene, dt=0.25, view=view)
        anim.fig.set_dpi(100)
        assert round(anim.fig.get_figwidth() * 100) == 1000
        px = anim.ax.get_window_extent(anim.fig.canvas.get_renderer()).width
        k, _ = to_unit(1.0, Kind.LENGTH, anim._S.system)
        widths = (anim.limits[:, 1] - anim.limits[:, 0] if anim.limits is not None
                  else np.full(len(anim), np.ptp(anim.ax.get_xlim())))
        length_px[view] = combination * k * px / widths  # per frame
        impact = int(np.flatnonzero(anim.times == 0.0)[0])
        length_px[view + " at impact"] = length_px[view][impact]
    assert length_px["follow"].min() > 150.0
    assert length_px["follow at impact"] > 2.5 * length_px["scene at impact"]


def test_camera_limits_hold_their_box_and_are_smoothed():
    from crashsim.animation import camera_limits

    t = np.arange(0.0, 4.0, 0.1)
    boxes = np.zeros((len(t), 4))
    boxes[:, 2:] = 4.0
    boxes[t >= 2.0] += [30.0, 0.0, 30.0, 0.0]  # the vehicle jumps 30 m at t = 2 s
    lim = camera_limits(t, boxes, 0.5, window=0.5, pad=3.0, margin=0.1, min_width=10.0)
    for (x0, y0, x1, y1), (a, b, c, d) in zip(boxes, lim):
        e = 1e-9  # round-off
        assert a <= x0 - 3.4 + e and b >= x1 + 3.4 - e and c <= y0 - 3.4 + e and d >= y1 + 3.4 - e
        assert (d - c) == pytest.approx(0.5 * (b - a))
    centre = 0.5 * (lim[:, 0] + lim[:, 1])
    # a still box: a still camera, exactly centred
    np.testing.assert_allclose(centre[t < 1.45], 2.0)
    # the size anticipates a change two windows ahead (the centre moves from 1.5 s, the size from 0.5 s)
    np.testing.assert_allclose(lim[t < 0.45, 1] - lim[t < 0.45, 0], lim[0, 1] - lim[0, 0])
    # the jump spread over the window: no step between frames larger than 30 m / (2 x 0.5 s / 0.1 s) * 1.01
    assert np.max(np.abs(np.diff(centre))) <= 30.0 / 11 * 1.01
    assert lim[0, 1] - lim[0, 0] >= 10.0


def test_follow_gif_is_drawn_whole_at_each_frame(tmp_path):
    scene = _scene(INTERSECTION)
    out = animate_scene(scene, tmp_path / "f.gif", dt=DT, dpi=30, legend="none")
    anim = scene_animation(scene, dt=DT, legend="none")
    assert anim.ax.get_legend() is None
    w, h = anim.fig.get_size_inches()
    with Image.open(out) as im:
        assert im.size == (round(w * 30), round(h * 30)) and im.n_frames == len(anim)
        im.seek(0)
        first = np.asarray(im.convert("RGB"), dtype=int)
        im.seek(len(anim) - 1)
        last = np.asarray(im.convert("RGB"), dtype=int)
    # the view moved: the tick labels, grid and fixed layer moved with it, not only the outlines
    changed = np.any(first != last, axis=2)
    assert changed.mean() > 0.2


def test_follow_gif_keeps_its_legend_in_every_frame(tmp_path):
    """The follow view draws its legend (outside the view, the same in every frame) once and pastes it."""
    scene = _scene(INTERSECTION)
    anim = scene_animation(scene, dt=DT)
    anim.fig.set_dpi(40)
    anim.fig.canvas.draw()
    box = anim.ax.get_legend().get_window_extent(anim.fig.canvas.get_renderer())
    h = round(anim.fig.get_figheight() * 40)
    out = animate_scene(scene, tmp_path / "l.gif", dt=DT, dpi=40)
    with Image.open(out) as im:
        for k in (1, im.n_frames - 1):
            im.seek(k)
            px = np.asarray(im.convert("L"), dtype=int)
            region = px[h - int(box.y1):h - int(box.y0), int(box.x0):int(box.x1)]
            assert (region < 128).mean() > 0.02, f"frame {k}: no legend drawn"


@pytest.mark.parametrize("kwargs, field", [({"view": "camera"}, "view"), ({"legend": "outside"}, "legend")])
def test_bad_view_or_legend_is_named(kwargs, field):
    with pytest.raises(ScenarioError, match=rf"^{field}: .* is unknown; allowed "):
        scene_animation(_scene(INTERSECTION), dt=DT, **kwargs)


def test_us_units_scale_the_outlines():
    scene = _scene(INTERSECTION)
    anim = scene_animation(scene, dt=DT, system="US")
    k, label = to_unit(1.0, Kind.LENGTH, "US")
    assert label == "ft" and anim.ax.get_xlabel() == "X [ft]"
    anim.frame(2)
    r, name, body, br = _bodies(scene)[0]
    x, y, heading = np.asarray(br.sol(min(anim.times[2], r.t_end)), dtype=float)[:3]
    np.testing.assert_allclose(_vertices(anim.outlines[name]), _corners(body, (x, y), heading, k), atol=1e-9)


def test_static_layer_is_the_scene_figure_without_ghosts():
    scene = _scene(INTERSECTION)
    anim = scene_animation(scene, dt=DT)
    gids = [p.get_gid() or "" for p in anim.ax.patches]
    assert not any(g.startswith("outline:ghost:") for g in gids)
    for _, name, _, _ in _bodies(scene):
        assert f"outline:impact:{name}" in gids and f"outline:rest:{name}" in gids
    # plot_scene(times=()) does not announce ghosts it does not draw
    texts = [t.get_text() for t in plot_scene(scene, times=()).get_legend().get_texts()]
    assert not any(t.startswith("intermediate") for t in texts)
    texts = [t.get_text() for t in plot_scene(scene, times=[1.0]).get_legend().get_texts()]
    assert "intermediate, at the given times" in texts


def test_a_scene_without_runout_is_refused():
    scene = _scene(TABLE6)
    assert scene.runout is None
    with pytest.raises(ScenarioError, match=r"^runout: .*no run-out \(impact only\).*nothing to animate"):
        scene_animation(scene)


# -- files ----------------------------------------------------------------------------------

def test_gif_has_one_frame_per_time_and_plays_in_real_time(tmp_path):
    scene = _scene(INTERSECTION)
    out = animate_scene(scene, tmp_path / "sub" / "scene.gif", dt=DT, speed=2.0, dpi=40)
    assert out == tmp_path / "sub" / "scene.gif"
    n = len(frame_times(_run_end(scene), DT))
    fps = 2.0 / DT
    with Image.open(out) as im:
        assert im.n_frames == n
        durations = []
        for k in range(im.n_frames):
            im.seek(k)
            durations.append(im.info["duration"])
    assert durations[:-1] == [int(1000 / fps)] * (n - 1)
    # the last frame is held about HOLD seconds (identical frames merged by the GIF encoder)
    assert durations[-1] == int(1000 / fps) * math.ceil(HOLD * fps)


def test_gif_is_written_at_the_requested_dpi(tmp_path):
    scene = _scene(INTERSECTION)
    anim = scene_animation(scene, dt=2.0)
    w, h = anim.fig.get_size_inches()
    out = animate_scene(scene, tmp_path / "a.gif", dt=2.0, dpi=30)
    with Image.open(out) as im:
        assert im.size == (round(w * 30), round(h * 30))
        assert im.n_frames == len(anim)


@pytest.mark.skipif(not mpl_animation.writers.is_available("ffmpeg"), reason="ffmpeg not installed")
def test_mp4_where_ffmpeg_is_available(tmp_path):  # pragma: no cover - depends on the machine
    out = animate_scene(_scene(INTERSECTION), tmp_path / "a.mp4", dt=DT, dpi=40)
    assert out.stat().st_size > 0


def test_formats_follow_ffmpeg(monkeypatch):
    assert animation_formats()[0] == ".gif"
    monkeypatch.setattr(mpl_animation.writers, "is_available", lambda name: name == "ffmpeg")
    assert animation_formats() == (".gif", ".mp4")
    monkeypatch.setattr(mpl_animation.writers, "is_available", lambda name: False)
    assert animation_formats() == (".gif",)


@pytest.mark.parametrize("kwargs, field", [({"speed": 0.0}, "speed"), ({"speed": float("nan")}, "speed"),
                                           ({"dpi": 0}, "dpi"), ({"dpi": 72.5}, "dpi"), ({"dt": -1.0}, "dt"),
                                           ({"t_end": -1.0}, "t_end"), ({"system": "metric"}, "system")])
def test_bad_arguments_are_named(tmp_path, kwargs, field):
    with pytest.raises(ScenarioError, match=rf"^{field}: "):
        animate_scene(_scene(INTERSECTION), tmp_path / "a.gif", **kwargs)
    assert not (tmp_path / "a.gif").exists()


# -- command line ---------------------------------------------------------------------------

def test_cli_writes_the_gif(tmp_path, capsys):
    out = tmp_path / "scene.gif"
    code = main(["animate", str(INTERSECTION), "-o", str(out), "--dt", "0.5 s", "--dpi", "30", "--units", "US"])
    assert code == 0
    assert capsys.readouterr().out == f"wrote {out}\n"
    with Image.open(out) as im:
        assert im.n_frames == len(frame_times(_run_end(_scene(INTERSECTION)), 0.5))


@pytest.fixture
def no_run(monkeypatch):
    """Fail if the scene is run: format errors must come before anything long."""
    import crashsim.scene

    def refuse(*args, **kwargs):
        raise AssertionError("the scene was run before the output format was checked")

    monkeypatch.setattr(crashsim.scene, "run_scene", refuse)


def test_cli_bad_suffix_exits_2_before_running(tmp_path, capsys, no_run):
    code = main(["animate", str(INTERSECTION), "-o", str(tmp_path / "scene.png")])
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("crashsim: input error: -o: ") and "scene.png" in err and "'.png'" in err
    assert "formats that can be written here: .gif" in err
    assert len(err.strip().splitlines()) == 1


def test_cli_mp4_without_ffmpeg_exits_2(tmp_path, capsys, monkeypatch, no_run):
    monkeypatch.setattr(mpl_animation.writers, "is_available", lambda name: False)
    code = main(["animate", str(INTERSECTION), "-o", str(tmp_path / "scene.mp4")])
    assert code == 2
    err = capsys.readouterr().err
    assert "-o: " in err and "scene.mp4" in err and "ffmpeg" in err
    assert err.rstrip().endswith("formats that can be written here: .gif")


@pytest.mark.parametrize("dt, message", [("0 s", "not a positive time"), ("0.5", "has no unit"),
                                         ("2 m", "expected a time"), ("1 ms", r"gives 29\d\d frames")])
def test_cli_bad_dt_exits_2_naming_it(tmp_path, capsys, dt, message):
    """A bad --dt is refused in one line; 1 ms over the scene's 2.95 s run-out is too many frames (the
    count follows the run-out's duration)."""
    out = tmp_path / "scene.gif"
    code = main(["animate", str(INTERSECTION), "-o", str(out), "--dt", dt])
    assert code == 2
    err = capsys.readouterr().err
    assert "--dt: " in err and re.search(message, err)
    # the first run on a new machine compiles the kernels first (its progress lines are not the error)
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("crashsim: compil")]
    assert "and >= 0 s" not in err and len(lines) == 1
    assert not out.exists()


def test_cli_scene_without_runout_exits_2(tmp_path, capsys):
    code = main(["animate", str(TABLE6), "-o", str(tmp_path / "a.gif")])
    assert code == 2
    assert "runout: " in capsys.readouterr().err



# -- results appear at their time ---------------------------------------------------------------

def _result_artists(ax):
    """The impact's results on the figure: delta-v and PDOF arrows, their labels, the contact point."""
    arrows = [p for p in ax.patches if (p.get_gid() or "").startswith(("arrow:delta-v:", "arrow:pdof:"))]
    labels = [t for t in ax.texts if (t.get_gid() or "").startswith(("label:delta-v", "label:pdof"))]
    return arrows, labels


def _drawn(anim, artist) -> bool:
    """Whether the artist is drawn on the frame (visible, and among the artists of the figure)."""
    return artist.get_visible() and artist.get_figure(root=True) is anim.fig


def test_impact_results_are_absent_before_the_impact_and_shown_from_it():
    """The truck that brakes into a car: the approach frames (t < 0) show no delta-v or PDOF arrow
    nor their labels; the frame at the impact (t = 0) and after it show them all."""
    scene = _scene(TRUCK)
    anim = scene_animation(scene, dt=DT, view="scene")
    try:
        arrows, labels = _result_artists(anim.ax)
        assert {p.get_gid() for p in arrows} >= {"arrow:delta-v:car", "arrow:pdof:car"}
        assert len(labels) == len(arrows)  # one label per arrow
        times = anim.times
        assert times[0] < 0.0 and 0.0 in times
        k0 = int(np.flatnonzero(times == 0.0)[0])
        anim.frame(0)  # the start of braking
        assert not any(_drawn(anim, a) for a in [*arrows, *labels])
        anim.frame(k0 - 1)  # the last frame before the impact
        assert times[k0 - 1] < 0.0
        assert not any(_drawn(anim, a) for a in [*arrows, *labels])
        # from the impact on, every arrow and label (and after it, to the last frame)
        for k, expected in ((k0 - 1, False), (k0, True), (len(times) - 1, True)):
            anim.frame(k)
            assert all(_drawn(anim, a) for a in [*arrows, *labels]) == expected, times[k]
        # every artist the animation shows from a time is among those it redraws per frame
        changing = set(map(id, anim.changing))
        assert all(id(a) in changing for a in [*arrows, *labels])
    finally:
        import matplotlib.pyplot as plt

        plt.close(anim.fig)


def test_results_on_the_first_frame_of_a_scene_without_approach_are_shown():
    """Without an approach the first frame is the impact itself (t = 0): the arrows are there."""
    anim = scene_animation(_scene(INTERSECTION), dt=DT, view="scene")
    try:
        arrows, labels = _result_artists(anim.ax)
        assert arrows and anim.times[0] == 0.0
        anim.frame(0)
        assert all(a.get_visible() for a in [*arrows, *labels])
    finally:
        import matplotlib.pyplot as plt

        plt.close(anim.fig)
