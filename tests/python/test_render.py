"""sluice.Renderer: frames drawn offscreen into numpy images, the same
picture `sluice render` writes for the same frame, size and camera."""
import subprocess

import matplotlib.image
import numpy as np
import pytest

import sluice


@pytest.fixture(scope="module")
def renderer(converted):
    return sluice.Renderer(converted, size=(320, 180))




def test_a_render_is_the_cli_picture(renderer, converted, sluice_exe, tmp_path):
    img = renderer.render(12)
    assert img.shape == (180, 320, 4) and img.dtype == np.uint8
    out = tmp_path / "cli.png"
    subprocess.run([str(sluice_exe), "render", str(converted), "--frames", "12", "--size", "320x180", "-o", str(out),
                    "--camera", renderer.camera, "-q"], check=True)
    cli = np.rint(matplotlib.image.imread(out) * 255).astype(np.uint8)
    assert cli.shape == img.shape
    diff = np.abs(cli.astype(int) - img.astype(int))
    # Same stream, same look, same camera: equal up to the GPU's rounding.
    assert diff.max() <= 2, (diff.max(), (diff > 2).sum())


def test_frames_colour_and_lod_change_the_picture(renderer, converted):
    first, last = renderer.render(0), renderer.render(-1)
    assert np.abs(first.astype(int) - last.astype(int)).max() > 50  # the dam broke
    coloured = sluice.Renderer(converted, size=(320, 180), color="rho")
    assert coloured.color == "rho"
    assert np.abs(coloured.render(-1).astype(int) - last.astype(int)).max() > 50
    # The convenience function: the same picture as a Renderer with its arguments.
    np.testing.assert_array_equal(sluice.render(sluice.open(converted), -1, size=(320, 180)), last)
    no_ground = renderer.render(-1, ground=False)
    assert not np.array_equal(no_ground, last)
    thin = renderer.render(-1, lod_level=0.3)
    assert thin.shape == last.shape
    again = renderer.render(-1)
    np.testing.assert_array_equal(again, last)  # nothing left over from the other looks


def test_auto_draws_the_samples_frames_as_ellipsoids_and_spheres_differ(renderer, converted, sluice_exe, tmp_path):
    # particles='auto', the default: the sample's frames hold far fewer than 2M particles.
    auto = renderer.render(12)
    ellipsoids = sluice.Renderer(converted, size=(320, 180), particles="ellipsoids")
    np.testing.assert_array_equal(ellipsoids.render(12, camera=renderer.camera), auto)
    spheres = sluice.Renderer(converted, size=(320, 180), particles="spheres").render(12, camera=renderer.camera)
    assert np.abs(auto.astype(int) - spheres.astype(int)).max() > 30
    out = tmp_path / "cli.png"
    subprocess.run([str(sluice_exe), "render", str(converted), "--frames", "12", "--size", "320x180", "-o", str(out),
                    "--camera", renderer.camera, "--particles", "spheres", "-q"], check=True)
    cli = np.rint(matplotlib.image.imread(out) * 255).astype(np.uint8)
    assert np.abs(cli.astype(int) - spheres.astype(int)).max() <= 2
    with pytest.raises(ValueError, match="particles"):
        sluice.Renderer(converted, size=(64, 64), particles="cubes")


def test_a_given_camera_is_used(renderer):
    renderer.render(5, camera="eye=0.5,-3,1;target=0.5,0.5,0.2;fov=30")
    assert "eye=0.5,-3,1" in renderer.camera.replace(" ", "")
    with pytest.raises(ValueError, match="camera"):
        renderer.render(5, camera="eye=banana")


def test_bad_requests(renderer, converted, tmp_path):
    with pytest.raises(IndexError):
        renderer.render(13)
    with pytest.raises(KeyError, match="vorticity"):
        sluice.Renderer(converted, size=(64, 64), color="vorticity")
    with pytest.raises(ValueError, match="display"):
        renderer.render(0, display="sparkly")
    with pytest.raises(ValueError, match="size"):
        sluice.Renderer(tmp_path / "x.sluice", size=(2, 2))
    with pytest.raises(FileNotFoundError):
        sluice.Renderer(tmp_path / "missing.sluice")


def test_render_takes_what_open_takes(sample_dir, tmp_path):
    import shutil

    for f in sample_dir.glob("*.vtu"):
        shutil.copy(f, tmp_path / f.name)
    img = sluice.render(str(tmp_path / "*.vtu"), 12, size=(64, 48))
    assert img.shape == (48, 64, 4) and len(np.unique(img.reshape(-1, 4), axis=0)) > 10
