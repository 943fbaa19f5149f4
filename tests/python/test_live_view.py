"""sluice.LiveView offscreen: frames pushed from numpy are drawn, recorded
as they were pushed, and dropped only as the counters say."""
import numpy as np
import pytest

import sluice


def block(step, n_side=24, spacing=0.02):
    """A block of water that slides along x, and each particle's speed."""
    g = (np.indices((n_side, n_side, n_side)).reshape(3, -1).T + 0.5) * spacing
    x = g.astype(np.float32) + np.float32([0.01 * step, 0, 0])
    return x, np.full(len(x), 0.1 * step, dtype=np.float32)


BOUNDS = ((0, 0, 0), (1, 0.6, 0.6))


def test_every_frame_is_drawn_and_recorded_with_keep_all(tmp_path):
    rec = tmp_path / "live.sluice"
    with sluice.LiveView(BOUNDS, window=False, size=(160, 120), spacing=0.02, attributes=["speed"], color="speed",
                         record=rec, keep_all=True) as view:
        assert view.image() is None
        for i in range(6):
            x, s = block(i)
            assert view.push(x, time=0.1 * i, speed=s)
    assert (view.pushed, view.shown, view.dropped) == (6, 6, 0)
    assert not view.open
    img = view.image()
    assert img.shape == (120, 160, 4)
    assert len(np.unique(img.reshape(-1, 4), axis=0)) > 20  # a picture, not a cleared image
    seq = sluice.open(rec)
    assert len(seq) == 6 and seq.attributes == ["speed"]
    np.testing.assert_allclose(seq.times, 0.1 * np.arange(6), rtol=0, atol=1e-12)
    f = seq[5]
    x, s = block(5)
    assert len(f) == len(x)
    # Positions come back quantized (within 1/1024 of the spacing), in the
    # recording's own order: compare sorted coordinates.
    for a in range(3):
        np.testing.assert_allclose(np.sort(f.positions[:, a]), np.sort(x[:, a]), atol=0.02 / 1000)
    np.testing.assert_allclose(f["speed"], 0.5, atol=1e-3)


def test_a_view_that_falls_behind_drops_and_says_so(tmp_path):
    rec = tmp_path / "drops.sluice"
    view = sluice.LiveView(BOUNDS, window=False, size=(160, 120), spacing=0.02, record=rec)
    for i in range(40):
        assert view.push(block(i % 8)[0], time=float(i))
    view.close()
    assert view.pushed == 40
    assert view.shown + view.dropped == 40
    seq = sluice.open(rec)
    assert len(seq) == view.shown  # what was drawn was recorded, nothing else
    assert seq.times[-1] == 39.0  # the newest frame is never the one dropped
    assert list(seq.times) == sorted(seq.times)
    assert view.push(block(0)[0]) is False  # closed: nothing more is taken


def test_bad_frames_raise_at_the_push_that_brought_them():
    with sluice.LiveView(BOUNDS, window=False, size=(64, 64), attributes=["speed"]) as view:
        x, s = block(0)
        with pytest.raises(ValueError, match="N, 3"):
            view.push(x[:, :2], speed=s)
        bad = x.copy()
        bad[7, 1] = np.nan
        with pytest.raises(ValueError, match="particle 7"):
            view.push(bad, speed=s)
        with pytest.raises(ValueError, match="speed"):
            view.push(x, speed=s[:-1])
        bad_speed = s.copy()
        bad_speed[11] = np.inf
        with pytest.raises(ValueError, match="'speed': particle 11"):
            view.push(x, speed=bad_speed)
        with pytest.raises(TypeError, match="missing attribute 'speed'"):
            view.push(x)
        with pytest.raises(TypeError, match="unexpected keyword 'sped'.*speed"):
            view.push(x, sped=s)
        with pytest.raises(ValueError, match="without ids=True"):
            view.push(x, ids=np.arange(len(x)), speed=s)
        assert view.push(x, speed=s)
        assert view.push(x, speed=s)  # the frames before were refused whole: nothing bad reached the view
    with sluice.LiveView(BOUNDS, window=False, size=(64, 64), ids=True) as view:
        x, _ = block(0)
        with pytest.raises(ValueError, match="ids=True"):
            view.push(x)
        assert view.push(x, ids=np.arange(len(x)))
    with pytest.raises(ValueError, match="bounds"):
        sluice.LiveView(((0, 0, 0), (0, 1, 1)), window=False)
    with pytest.raises(KeyError, match="rho"):
        sluice.LiveView(BOUNDS, window=False, attributes=["speed"], color="rho")


def test_without_a_display_the_error_says_window_false():
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    code = ("import sluice\n"
            "try:\n"
            "    sluice.LiveView(((0, 0, 0), (1, 1, 1)))\n"
            "except sluice.Error as e:\n"
            "    print(e)\n")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert "window=False" in out.stdout, out.stdout + out.stderr
