"""The Python module against the sluice command: the same values for every
particle, arrays that outlive their sequence, streaming equal to random
access, LOD levels that read less, and the errors a script sees."""
import csv
import gc
import json
import os
import shutil
import subprocess

import numpy as np
import pytest

import sluice


def export_csv(sluice_exe, path, frame, out, lod_level=1.0):
    subprocess.run([str(sluice_exe), "export", str(path), "-o", str(out), "--frames", str(frame),
                    "--lod-level", str(lod_level), "-q", "-f"], check=True)
    with open(out, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], np.array(rows[1:], dtype=np.float64)
    return {name: body[:, i] for i, name in enumerate(header)}


def test_the_sequence_describes_the_file(converted):
    seq = sluice.open(converted)
    assert len(seq) == 13
    assert seq.attributes == ["rho", "p"]
    assert np.all(np.diff(seq.times) > 0)
    assert seq.up == "+z"
    assert seq.spacing > 0 and seq.radius > 0
    lo, hi = seq.bounds
    assert all(a < b for a, b in zip(lo, hi))
    info = seq.info()
    assert info["frames"] == 13 and info["attributes"] == ["rho", "p"]
    assert info["particles"] == int(seq.counts.sum())
    assert set(seq.layers) <= {"all", "surface", "interior", "blobs"}


@pytest.mark.parametrize("frame", [0, 6, 12])
def test_every_particle_equals_sluice_export(converted, sluice_exe, tmp_path, frame):
    ref = export_csv(sluice_exe, converted, frame, tmp_path / "f.csv")
    f = sluice.open(converted)[frame]
    assert f.index == frame
    assert f.positions.dtype == np.float32 and f.positions.shape == (len(ref["x"]), 3)
    # The CSV holds each float32 in its shortest exact form: equal, not close.
    np.testing.assert_array_equal(f.positions[:, 0], ref["x"].astype(np.float32))
    np.testing.assert_array_equal(f.positions[:, 1], ref["y"].astype(np.float32))
    np.testing.assert_array_equal(f.positions[:, 2], ref["z"].astype(np.float32))
    np.testing.assert_array_equal(f.lod, ref["lod"].astype(np.uint16))
    np.testing.assert_array_equal(f["rho"], ref["rho"].astype(np.float32))
    np.testing.assert_array_equal(f.attributes["p"], ref["p"].astype(np.float32))


def test_a_lod_level_keeps_exports_particles_and_reads_less(converted, sluice_exe, tmp_path):
    ref = export_csv(sluice_exe, converted, 3, tmp_path / "thin.csv", lod_level=0.25)
    seq = sluice.open(converted)
    thin, whole = seq.frame(3, lod_level=0.25), seq.frame(3)
    assert 0.15 * len(whole) < len(thin) < 0.35 * len(whole)
    # The same particles (tiers may order them differently within a chunk).
    got = sorted(zip(thin.lod.tolist(), thin.positions[:, 0].tolist(), thin["rho"].tolist()))
    want = sorted(zip(ref["lod"].astype(np.uint16).tolist(), ref["x"].astype(np.float32).tolist(),
                      ref["rho"].astype(np.float32).tolist()))
    assert got == want
    # The sample is a lattice: its cells are written whole (tiers would cost
    # more than they save), so nothing less can be read.
    assert thin.bytes_read == whole.bytes_read


def test_a_lod_level_reads_only_its_tiers(tmp_path):
    # Scattered particles with ids: cells are written as LOD tiers.
    rng = np.random.default_rng(7)
    n = 60000
    xyz = rng.random((n, 3)).astype(np.float32) * np.float32([1, 1, 0.3])
    with open(tmp_path / "scatter.csv", "w") as f:
        f.write("x,y,z,id\n")
        for i, (x, y, z) in enumerate(xyz.tolist()):
            f.write(f"{x},{y},{z},{i * 7919 + 13}\n")
    sluice.convert(str(tmp_path / "scatter.csv"), tmp_path / "scatter.sluice", spacing=0.01, isolate=False)
    seq = sluice.open(tmp_path / "scatter.sluice")
    whole, tenth = seq.frame(0), seq.frame(0, lod_level=0.1)
    assert len(whole) == n
    assert 0.07 * n < len(tenth) < 0.13 * n
    assert tenth.bytes_read < 0.3 * whole.bytes_read, (tenth.bytes_read, whole.bytes_read)


def test_arrays_outlive_their_sequence_and_frame(converted):
    seq = sluice.open(converted)
    f = seq[5]
    expected = f.positions.copy()
    positions, rho = f.positions, f["rho"]
    assert not positions.flags.owndata  # handed over, not copied
    del f, seq
    gc.collect()
    np.testing.assert_array_equal(positions, expected)
    assert np.isfinite(rho).all() and rho.min() > 900


def test_streaming_equals_random_access(converted):
    seq = sluice.open(converted)
    streamed = list(seq.frames(1, None, 3, lod_level=0.5, attributes=["p"]))
    assert [f.index for f in streamed] == [1, 4, 7, 10]
    for f in streamed:
        g = seq.frame(f.index, lod_level=0.5, attributes=["p"])
        assert list(f.attributes) == ["p"]
        np.testing.assert_array_equal(f.positions, g.positions)
        np.testing.assert_array_equal(f.lod, g.lod)
        np.testing.assert_array_equal(f["p"], g["p"])
        assert f.time == g.time
    every = [f.index for f in seq]
    assert every == list(range(13))
    stream = seq.frames(-2)
    del seq
    gc.collect()
    assert [f.index for f in stream] == [11, 12]  # a stream outlives its sequence


def test_streamed_arrays_are_lent_and_outlive_their_stream(converted):
    seq = sluice.open(converted)
    # A small window: the first frames are lent (arrays over the pipeline's
    # buffers), the rest of a kept list are copies, and nothing waits forever.
    stream = seq.frames(window=4)
    kept = list(stream)
    assert [f.index for f in kept] == list(range(13))
    expected = [seq.frame(i) for i in range(13)]
    del stream, seq
    gc.collect()
    for f, g in zip(kept, expected):
        np.testing.assert_array_equal(f.positions, g.positions)
        np.testing.assert_array_equal(f.lod, g.lod)
        np.testing.assert_array_equal(f.layer, g.layer)
        np.testing.assert_array_equal(f["rho"], g["rho"])
    # A loop that lets each frame go keeps every frame lent.
    seq = sluice.open(converted)
    total = 0
    for f in seq.frames(window=4):
        total += len(f.positions)
    assert total == sum(len(g.positions) for g in expected)


def test_surface_layers(converted):
    seq = sluice.open(converted)
    whole, surface = seq.frame(12), seq.frame(12, layers="surface")
    assert set(np.unique(whole.layer)) <= {0, 1, 2}
    assert 3 not in set(np.unique(whole.layer))
    if "blobs" in seq.layers:
        assert 3 in set(np.unique(surface.layer))
        assert len(surface) < len(whole)


def test_bad_requests_raise_what_a_script_expects(converted, tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        sluice.open(tmp_path / "missing.sluice")
    not_sluice = tmp_path / "text.sluice"
    not_sluice.write_text("hello\n" * 100)
    with pytest.raises(sluice.Error, match="text.sluice"):
        sluice.open(not_sluice)
    seq = sluice.open(converted)
    with pytest.raises(IndexError):
        seq[13]
    assert seq[-1].index == 12
    with pytest.raises(KeyError, match="velocity"):
        seq.frame(0, attributes=["velocity"])
    with pytest.raises(ValueError, match="layers"):
        seq.frame(0, layers="interior")
    with pytest.raises(ValueError, match="lod_level"):
        seq.frame(0, lod_level=0)
    with pytest.raises(KeyError, match="rho"):
        seq[0]["vorticity"]


def test_a_damaged_frame_names_file_frame_and_chunk(converted, tmp_path):
    damaged = tmp_path / "damaged.sluice"
    shutil.copy(converted, damaged)
    with open(damaged, "r+b") as f:
        f.seek(os.path.getsize(damaged) // 2)
        byte = f.read(1)
        f.seek(-1, 1)
        f.write(bytes([byte[0] ^ 0x5A]))
    seq = sluice.open(damaged)
    failures = []
    for i in range(len(seq)):
        try:
            seq[i]
        except sluice.Error as e:
            failures.append((i, str(e)))
    assert len(failures) == 1, failures
    frame, message = failures[0]
    assert "damaged.sluice" in message and f"frame {frame}" in message and "chunk" in message
    with pytest.raises(sluice.Error, match=f"frame {frame}"):
        list(seq.frames())


def test_convert_reports_progress_and_stops_when_told(sample_dir, tmp_path):
    seen = []
    summary = sluice.convert(str(sample_dir / "dam_break_3d.pvd"), tmp_path / "a.sluice", progress=seen.append)
    assert [p["frames_done"] for p in seen] == list(range(1, 14))
    assert summary["frames"] == 13 and summary["up"] == "+z"
    assert all(p["frames"] == 13 for p in seen)

    class Stop(Exception):
        pass

    def stop_at_third(p):
        if p["frames_done"] == 3:
            raise Stop("enough")

    with pytest.raises(Stop, match="enough"):
        sluice.convert(str(sample_dir / "dam_break_3d.pvd"), tmp_path / "b.sluice", progress=stop_at_third)
    assert not (tmp_path / "b.sluice").exists()  # never a file that looks whole


def test_convert_errors_name_the_input(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z\n1,2\n")
    with pytest.raises(sluice.Error, match="bad.csv"):
        sluice.convert(str(bad), tmp_path / "out.sluice")
    with pytest.raises(ValueError, match="up"):
        sluice.convert(str(bad), tmp_path / "out.sluice", up="sideways")


def test_help_teaches():
    assert "lod_level" in sluice.Sequence.frame.__doc__
    assert "sluice.open(" in sluice.open.__doc__
    assert "progress" in sluice.convert.__doc__


def test_export_writes_what_sluice_export_writes(converted, sluice_exe, tmp_path):
    seq = sluice.open(converted)
    seen = []
    out = sluice.export(seq, tmp_path / "py" / "dam.vtp", frames=range(2, 5), progress=seen.append)
    assert out["frames"] == 3 and sorted(out["files"]) == [2, 3, 4]
    assert out["pvd"].endswith("dam.pvd") and os.path.exists(out["pvd"])
    assert [p["frames_done"] for p in seen] == [1, 2, 3]
    # One frame as CSV: byte for byte the file `sluice export` writes.
    sluice.export(str(converted), tmp_path / "py.csv", frames=[3], lod_level=0.5, attributes=["rho"])
    subprocess.run([str(sluice_exe), "export", str(converted), "-o", str(tmp_path / "cli.csv"), "--frames", "3",
                    "--lod-level", "0.5", "-a", "rho", "-q"], check=True)
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    with pytest.raises(sluice.Error, match="force=True"):
        sluice.export(seq, tmp_path / "py.csv", frames=[3])
    assert sluice.export(seq, tmp_path / "py.csv", frames=[4], force=True)["frames"] == 1
    with pytest.raises(IndexError):
        sluice.export(seq, tmp_path / "x.csv", frames=[13])
    with pytest.raises(sluice.Error, match="extension"):
        sluice.export(seq, tmp_path / "x.txt", frames=[1])


def test_open_converts_what_a_solver_wrote_once(sample_dir, tmp_path):
    # A copy of the sample's files: the cache goes beside them.
    for f in sample_dir.glob("*.vtu"):
        shutil.copy(f, tmp_path / f.name)
    seen = []
    seq = sluice.open(str(tmp_path / "*.vtu"), progress=seen.append)
    assert len(seq) == 13 and seen[-1]["frames_done"] == 13
    assert (tmp_path / ".sluice-cache").is_dir()
    again = []
    assert len(sluice.open(str(tmp_path / "*.vtu"), progress=again.append)) == 13
    assert again == []  # reused, not converted again
    temporary = sluice.open(tmp_path / "dam_break_3d_fluid_00000.vtu", cache=False)
    assert len(temporary) == 1 and len(temporary[0]) == 9360
    # A cache folder of the user's choosing: nothing written beside the input.
    solver = tmp_path / "solver"
    solver.mkdir()
    for f in sample_dir.glob("*.vtu"):
        shutil.copy(f, solver / f.name)
    chosen = sluice.open(str(solver / "*.vtu"), cache_dir=tmp_path / "mine")
    assert len(chosen) == 13 and chosen.path.startswith(str(tmp_path / "mine"))
    assert not (solver / ".sluice-cache").exists()
    # export() takes what open() takes: the cached conversion is exported.
    summary = sluice.export(str(tmp_path / "*.vtu"), tmp_path / "out" / "f.csv", frames=[12])
    assert list(summary["files"]) == [12]


def test_convert_takes_the_command_lines_options(sample_dir, tmp_path):
    out = tmp_path / "gpu.sluice"
    sluice.convert(str(sample_dir / "dam_break_3d.pvd"), out, planes="gpu-decodable", chunk=1000, level=1,
                   tiers=False, layers=False, attributes=["rho"], isolate=False)
    info = sluice.open(out).info()
    assert info["frames"] == 13 and info["attributes"] == ["rho"]
    assert sluice.open(out).layers == ["all"]  # unclassified: layers=False
    with pytest.raises(ValueError, match="planes"):
        sluice.convert(str(sample_dir / "dam_break_3d.pvd"), tmp_path / "x.sluice", planes="tiny")
    with pytest.raises(ValueError, match="level"):
        sluice.convert(str(sample_dir / "dam_break_3d.pvd"), tmp_path / "x.sluice", level=40)


def test_a_looping_stream_goes_round(converted):
    seq = sluice.open(converted)
    stream = seq.frames(0, 3, loop=True, window=2)
    assert [next(stream).index for _ in range(7)] == [0, 1, 2, 0, 1, 2, 0]
    with pytest.raises(TypeError, match="no length"):
        len(stream)


def test_counts_and_particles_agree_in_every_interface(converted, sluice_exe):
    seq = sluice.open(converted)
    info = seq.info()
    cli = json.loads(subprocess.run([str(sluice_exe), "info", "--json", str(converted)], check=True,
                                    capture_output=True, text=True).stdout)
    lengths = [len(seq[i]) for i in range(len(seq))]
    assert list(seq.counts) == lengths  # surface and interior; blobs are not particles
    assert [f["particles"] for f in cli["frames"]] == lengths
    assert info["particles"] == sum(lengths) == cli["particles_total"]
    # The surface read adds blobs, which stand in for interior particles.
    f = seq.frame(3, layers="surface")
    assert (f.layer == 3).sum() > 0 and (f.layer == 2).sum() == 0


def test_an_input_without_times_has_none(tmp_path):
    for i in range(3):
        (tmp_path / f"part_{i}.csv").write_text("x,y,z\n" + "".join(f"{0.01 * k},{0.02 * i},0\n" for k in range(50)))
    out = tmp_path / "untimed.sluice"
    sluice.convert(tmp_path / "part_*.csv", out)  # a pathlib.Path input (a glob) is taken too
    seq = sluice.open(out)
    assert seq.times is None and seq.info()["times"] == "none"
    assert seq[1].time is None and "no time" in repr(seq[1])
    assert all(f.time is None for f in seq)
    timed = tmp_path / "timed.sluice"
    sluice.convert(str(tmp_path / "part_*.csv"), timed, dt=0.5)
    assert list(sluice.open(timed).times) == [0.0, 0.5, 1.0] and sluice.open(timed)[2].time == 1.0


def test_writers_keep_an_existing_output_unless_forced(sample_dir, tmp_path):
    out = tmp_path / "kept.sluice"
    out.write_bytes(b"the user's own file")
    with pytest.raises(sluice.Error, match="force=True"):
        sluice.convert(str(sample_dir / "dam_break_3d.pvd"), out)
    assert out.read_bytes() == b"the user's own file"
    with pytest.raises(sluice.Error, match="force=True"):
        sluice.LiveView(((0, 0, 0), (1, 1, 1)), window=False, record=out)
    assert out.read_bytes() == b"the user's own file"
    summary = sluice.convert(str(sample_dir / "dam_break_3d.pvd"), out, force=True)
    assert summary["frames"] == 13 and len(sluice.open(out)) == 13


def test_indices_slices_and_ranges_behave_as_python_does(converted):
    seq = sluice.open(converted)
    n = len(seq)
    with pytest.raises(IndexError, match=f"frame -{n + 1} is out of range"):
        seq[-(n + 1)]
    assert seq[-1].index == n - 1
    frames = seq[2:9:3]
    assert isinstance(frames, list) and [f.index for f in frames] == [2, 5, 8]
    assert [f.index for f in seq[-2:]] == [n - 2, n - 1]
    assert seq[5:2] == []
    with pytest.raises(ValueError, match="no frames in that range"):
        seq.frames(n + 5, 2)


def test_export_takes_any_iterable_of_frames_and_checks_levels_as_frame_does(converted, tmp_path):
    seq = sluice.open(converted)
    summary = sluice.export(seq, tmp_path / "g" / "f.csv", frames=(i for i in (1, 3)))
    assert sorted(summary["files"]) == [1, 3]
    with pytest.raises(ValueError, match="lod_level"):
        sluice.export(seq, tmp_path / "z.csv", frames=[0], lod_level=0)
    with pytest.raises(ValueError, match="lod_level"):
        seq.frame(0, lod_level=0)
    with pytest.raises(TypeError, match="frame numbers"):
        sluice.export(seq, tmp_path / "s.csv", frames=["0"])


def test_a_memory_cap_that_holds_no_frames_says_so(converted):
    seq = sluice.open(converted)
    with pytest.raises(ValueError, match="less than two frames"):
        seq.frames(memory=1000)
    assert len(list(seq.frames(0, 3, memory=64 << 20))) == 3
