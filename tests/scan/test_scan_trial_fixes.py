"""A user trial's scanner defects: a killed scan's waveform temporary is removed by the next
write into its folder (named as every atomic write's temporary), and a flash array refuses
the beam settings it ignores, bounds its pixels' sub-rays by its own tolerance and records
what it sampled its pixels with."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import meshladar as ml

from meshladar.errors import EmptyScanWarning, MeshladarWarning, ParameterError
from meshladar.io import TEMPORARY_PREFIX, temporary_writer
from meshladar.scan import GeigerMode, Platform, ScanBeam, flash, raster, read_hdf5, scan
from meshladar.scan.files import WaveformSink
from meshladar.scan.footprint import pixel_offsets

from _scan_scenes import photoelectrons_by_hand, plate, scene, sensor

#: A child that opens a streaming waveform file, writes a block, says where its temporary
#: is, then waits on its stdin (for a SIGKILL, or for the test to close it).
_STREAMING_CHILD = """
import os, sys
import numpy as np
from meshladar.scan.files import WaveformSink
sink = WaveformSink(sys.argv[1])
sink.write(0, np.ones((4, 64)), np.zeros(4))
sink.file.flush()
print(os.path.basename(sink.partial), flush=True)
sys.stdin.read()
"""


def _streaming_child(path):
    """A child process streaming into ``path``, and its temporary's name (read once the
    child has written it: the test waits on that line, not on time)."""
    h5py = pytest.importorskip("h5py")
    assert h5py
    child = subprocess.Popen([sys.executable, "-c", _STREAMING_CHILD, str(path)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    return child, child.stdout.readline().strip()


def test_a_killed_scans_waveform_temporary_is_removed_by_the_next_scan_there(tmp_path):
    """``scan ... --waveforms bigw.h5`` killed by SIGKILL left ``bigw.h5.partial-<pid>``
    (16 MB in the trial) that no later write removed. Its temporary is now an atomic
    write's (``.meshladar-tmp-<pid>-…bigw.h5``): the next scan writing into that folder
    removes the dead writer's, and keeps a live writer's."""
    dead, dead_name = _streaming_child(tmp_path / "bigw.h5")
    live, live_name = _streaming_child(tmp_path / "other.h5")
    try:
        dead.kill()                                           # SIGKILL: no clean-up runs
        assert dead.wait() == -signal.SIGKILL
        assert dead_name.startswith(TEMPORARY_PREFIX) and dead_name.endswith("bigw.h5")
        assert temporary_writer(dead_name) == dead.pid
        assert temporary_writer(live_name) == live.pid
        assert sorted(os.listdir(tmp_path)) == sorted([dead_name, live_name])
        cloud = scan(scene(plate(50.0)), flash(2, 2, ifov_deg=0.1), Platform.static((0, 0, 0)),
                     sensor(), waveforms_file=tmp_path / "bigw.h5")
        assert sorted(os.listdir(tmp_path)) == sorted(["bigw.h5", live_name])
        back = read_hdf5(tmp_path / "bigw.h5")
        assert back.points.tobytes() == cloud.points.tobytes()
        assert len(back.waveforms) == 1 and back.waveforms[0].shape[0] == 4
    finally:
        live.communicate("")                                 # its stdin closed: it ends
        dead.communicate()
    assert live.returncode == 0


def test_the_waveform_sink_streams_into_a_temporary_of_its_own_pid(tmp_path):
    """While streaming, the only file is this process's temporary (its pid in the name,
    the permissions a new file gets); finished, the file alone; abandoned, nothing."""
    pytest.importorskip("h5py")
    sink = WaveformSink(tmp_path / "w.h5")
    (name,) = os.listdir(tmp_path)
    assert temporary_writer(name) == os.getpid() and name.endswith("w.h5")
    umask = os.umask(0o022)
    os.umask(umask)
    assert os.stat(tmp_path / name).st_mode & 0o777 == 0o666 & ~umask
    sink.write(0, np.ones((2, 8)), np.zeros(2))
    sink.abandon()
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("beam, field, value", [
    (ScanBeam(5e-4), "divergence", "0.0005"),
    (ScanBeam(0.0, profile="tophat"), "profile", "'tophat'"),
    (ScanBeam(0.0, sub_rays=4), "sub_rays", "4"),
    (ScanBeam(0.0, sub_rays=4, tol=0.001), "sub_rays", "4"),
])
def test_a_flash_scan_refuses_the_beam_settings_its_pixels_ignore(beam, field, value):
    """A flash pixel is lit uniformly over its IFOV and sampled to the beam's tol: a beam's
    divergence, profile or sub_rays changed nothing but were recorded in the file's
    info. Now refused, naming the field, its value and what flash uses."""
    with pytest.raises(ParameterError) as exc:
        scan(scene(plate(50.0)), flash(2, 2, ifov_deg=0.1), Platform.static((0, 0, 0)),
             sensor(beam=beam))
    msg = str(exc.value)
    assert msg.startswith(f"beam.{field}={value} does not apply to a flash array")
    assert "uniformly over their IFOV" in msg and f"beam.tol={beam.tol:g}" in msg


def test_a_flash_pixels_tolerance_is_bounded_by_its_own_sub_rays():
    """tol=0.001 was refused with the beam's "more than 4096 sub-rays per pulse" (a beam
    flash does not use), or, with sub_rays given, run at 500 x 500 sub-rays a pixel. The
    pixels' own bound: m = ceil(1/(2 tol)) <= 64 a side (4096 a pixel, a beam's most)."""
    with pytest.raises(ParameterError) as exc:
        scan(scene(plate(50.0)), flash(2, 2, ifov_deg=0.1), Platform.static((0, 0, 0)),
             sensor(beam=ScanBeam(0.0, tol=0.001)))
    assert str(exc.value) == (
        "beam.tol=0.001: a flash pixel is sampled by m x m sub-rays, m = ceil(1/(2 tol)) = "
        "500 (250000 a pixel), more than 64 x 64 = 4096; give beam.tol >= 0.0078125")
    with pytest.raises(ParameterError, match=r"^tol=0.0078: .* = 65 \(4225 a pixel\)"):
        pixel_offsets(0.0078)
    assert pixel_offsets(1 / 128).shape == (4096, 2)
    assert pixel_offsets(0.1).shape == (25, 2)


@pytest.mark.parametrize("tol, side", [(0.1, 5), (1 / 128, 64)])
def test_a_flash_scan_records_its_pixels_sampling_as_its_beam(tol, side):
    """The cloud's info says what the pixels were sampled with (the beam's description
    said one sub-ray), and the frame's photoelectrons are the same at either sampling (a
    plate filling the field)."""
    cloud = scan(scene(plate(50.0)), flash(2, 2, ifov_deg=0.1), Platform.static((0, 0, 0)),
                 sensor(beam=ScanBeam(0.0, tol=tol)), keep_waveforms=True)
    assert cloud.info["sensor"]["beam"] == {"profile": "flash pixel", "ifov_deg": 0.1,
                                            "tol": tol, "sub_rays": side * side,
                                            "side": side}
    coarse = scan(scene(plate(50.0)), flash(2, 2, ifov_deg=0.1), Platform.static((0, 0, 0)),
                  sensor(beam=ScanBeam(0.0, tol=0.5)), keep_waveforms=True)
    assert coarse.info["sensor"]["beam"]["sub_rays"] == 1
    assert cloud.waveforms[0].sum() == pytest.approx(coarse.waveforms[0].sum(), rel=1e-4)


#: The ring's and the wall's distances (m) and the hole's radius: a beam of 1/e² half-angle
#: 1e-2 rad lights both (footprint radius 0.1 m at the ring).
RING, WALL, HOLE = 10.0, 20.0, 0.05


def test_a_fixed_record_that_cuts_an_echo_drops_its_return_and_says_how_long_to_make_it():
    """A pulse through a hole in a ring at 10 m onto a wall at 20 m: its record starts at
    the ring's echo less 8 σ, so at 80 samples the wall's echo (66.7 ns = 133 samples
    later) lies past its end. The wall's return is dropped (it was reported at the
    record's end, metres short), the ring's kept at 10 m, and one RecordLengthWarning
    names the length that holds both: the wall's time less the ring's plus 16 σ, in
    samples, and one or two for the record's start on a sample (201.3 + 1 to 2, by hand).
    At that length both come back, at 10 and 20 m. Fewer samples than one echo takes
    (70 here: 16 σ of 2.12 ns at 2 GS/s, and 2) are refused before any ray is cast."""
    from meshladar.errors import RecordLengthWarning
    from meshladar.scan import ScanPattern

    sc = scene(plate(RING, hole=HOLE), plate(WALL))
    pat = ScanPattern([0.0], [[1.0, 0.0, 0.0]])
    beam = ScanBeam(1e-2, sub_rays=64)
    dt, sigma = 0.5e-9, 5e-9 / 2.3548200450309493
    by_hand = (2 * (WALL - RING) / 299_792_458.0 + 16 * sigma) / dt + 1
    with pytest.warns(RecordLengthWarning, match=r"echoes of 1 of 1 pulses") as caught:
        short = scan(sc, pat, Platform.static((0, 0, 0)), sensor(beam=beam, samples=80))
    assert len(caught) == 1
    need = int(str(caught[0].message).split("; samples=")[1].split()[0])
    assert by_hand <= need <= by_hand + 2
    np.testing.assert_allclose(short.points["range"], [RING], atol=0.02)
    whole = scan(sc, pat, Platform.static((0, 0, 0)), sensor(beam=beam, samples=need))
    np.testing.assert_allclose(np.sort(whole.points["range"]), [RING, WALL], atol=0.02)
    with pytest.raises(ParameterError, match=r"samples: a record of 69 samples cannot hold "
                                             r"one echo .* give 70 or more"):
        sensor(samples=69)


def test_record_runs_hold_at_most_their_budget_of_samples():
    """Pulses of one echo at 5 m or two (5 m and 1.5 km, ~20,000 samples apart) in an
    irregular order: record_blocks' runs cover the pulses in order, and each run's records
    as waveforms() makes them (its own length) hold at most the budget, but a run of one
    pulse; one run where the chunk fits."""
    from meshladar.scan._sampling import lit_spans
    from meshladar.scan.echoes import record_blocks, waveforms

    rng = np.random.default_rng(3)
    n, m, dt, sigma = 300, 4, 0.5e-9, 2.1e-9
    tau = np.full((n, m), 2 * 5.0 / 299_792_458.0)
    deep = rng.random(n) < 0.3
    tau[deep, 2:] = 2 * 1500.0 / 299_792_458.0
    pe = np.ones((n, m))
    pe[rng.random(n) < 0.1] = 0.0                                 # some pulses see nothing
    for budget in (60_000, 400_000, 10**8):
        runs = record_blocks(lit_spans(tau, pe), sigma, dt, None, budget)
        assert runs[0][0] == 0 and runs[-1][1] == n
        assert all(a[1] == b[0] for a, b in zip(runs, runs[1:]))
        for lo, hi in runs:
            waves, _ = waveforms(tau[lo:hi], pe[lo:hi], sigma, dt)
            assert waves.size <= budget or hi - lo == 1
        assert (len(runs) == 1) == (budget == 10**8)


def test_a_deep_scenes_records_in_runs_give_the_points_of_one(monkeypatch):
    """A raster across a plate's edge at 5 m onto a wall 1.5 km behind: the pulses that
    light both need records of ~20,000 samples, and one record length for the chunk made
    every record that long (2.1 GB for 1,500 pulses with the wall at 12 km). Made in runs
    of at most RECORD_SAMPLES samples (set to 200,000 here), the expected points are
    those of one run (to 1e-9 m), both surfaces at their distances. With noise each run
    draws its own (the records of two runs' like pulses differ), the same on one thread
    and two, and the same whether the records are kept or not (the runs depend on the
    echoes alone); kept, they come back a block a run, each pulse's record found by
    ``waveform``."""
    import trimesh

    import meshladar as ml
    from meshladar.scan import ScanPattern, raster
    from meshladar.scan import run as scan_run

    edge = trimesh.creation.box((0.01, 2.0, 2.0))
    edge.apply_translation((5.005, 1.0, 0.0))                       # y from 0 to 2
    sc = scene(edge, plate(1505.0, half=400.0))
    pat = raster(np.linspace(-2, 2, 200), [0.0], pulse_rate=1e4)
    beam = ScanBeam(1e-2, sub_rays=32)
    one = scan(sc, pat, Platform.static((0, 0, 0)), sensor(beam=beam), jobs=1)
    monkeypatch.setattr(scan_run, "RECORD_SAMPLES", 200_000)
    runs = scan(sc, pat, Platform.static((0, 0, 0)), sensor(beam=beam), jobs=1)
    assert len(runs) == len(one) > 200
    for name in ("range", "x", "y", "z", "intensity", "true_range"):
        np.testing.assert_allclose(runs.points[name], one.points[name], rtol=0, atol=1e-9)
    assert set(np.round(runs.points["true_range"], -1)) <= {0.0, 10.0, 1500.0, 1510.0}
    # measured, against the scene: the plate's face at x = 5 m (to 1 mm); the wall at
    # x = 1505 m, a point off by no more than its beam's sub-rays' slant can make it (the
    # point lies on the axis, its sub-rays up to 2 radii off it; 2 cm for the samples) and,
    # over the pulses, by the whole Gaussian footprint's mean slant 1505 w²/4 (to 1 cm:
    # 32 sub-rays sample it)
    pts, w = runs.points, beam.divergence
    near, az = pts["true_range"] < 100.0, np.abs(np.deg2rad(runs.points["scan_angle"]))
    assert near.sum() > 100 and (~near).sum() > 100
    np.testing.assert_allclose(pts["x"][near], 5.0, rtol=0, atol=1e-3)
    off = pts["x"][~near] - 1505.0
    slant = 1505.0 * (np.cos(az[~near]) / np.cos(az[~near] + 2 * w) - 1.0)
    assert np.all(np.abs(off) <= slant + 0.02)
    assert abs(np.median(off) - 1505.0 * w ** 2 / 4) < 0.01
    noisy = sensor(beam=beam, noise=ml.noise.Noise(background_rate=1e6))
    a = scan(sc, pat, Platform.static((0, 0, 0)), noisy, jobs=1, chunk_pulses=50)
    b = scan(sc, pat, Platform.static((0, 0, 0)), noisy, jobs=2, chunk_pulses=50)
    kept = scan(sc, pat, Platform.static((0, 0, 0)), noisy, jobs=1, chunk_pulses=50,
                keep_waveforms=True)
    for other in (b, kept):
        for name in a.points.dtype.names:                          # (a false alarm's nan)
            np.testing.assert_array_equal(a.points[name], other.points[name])
    sizes = [len(w) for w in kept.waveforms]
    assert sum(sizes) == 200 and len(sizes) > 200 // 50             # runs within chunks
    # 40 like pulses at the plate's edge (both echoes): each run's first record is the
    # same expected record, measured with the run's own noise
    like = ScanPattern(np.arange(40) * 1e-4, [[1.0, 0.0, 0.0]] * 40)
    same = scan(sc, like, Platform.static((0, 0, 0)), noisy, jobs=1, keep_waveforms=True)
    assert len(same.waveforms) >= 2
    firsts = [w[0] for w in same.waveforms]
    assert len({len(w) for w in firsts}) == 1 and not np.array_equal(firsts[0], firsts[1])


@pytest.mark.parametrize("kind", ["gaussian", "box", "box+response"])
def test_the_fewest_samples_hold_one_echo_of_any_shape(kind):
    """ScanSensor.echo_samples against the record a one-echo scan makes at the default
    length (its echo's support from its start on a sample): that record is echo_samples
    or one fewer long; at echo_samples a fixed record holds the echo (no warning, the
    plate at its distance), one fewer is refused. A 5 ns box pulse at 2 GS/s needs its
    10 samples and 2 (by hand), a Gaussian 16 σ and 2 (70), not 16 σ of the box's σ."""
    from meshladar.scan import ScanPattern
    from meshladar.waveforms import GaussianPulse, SampledPulse

    box = SampledPulse(np.ones(10), interval=0.5e-9)
    kw = {"gaussian": {}, "box": {"pulse": box},
          "box+response": {"pulse": box, "response": GaussianPulse(1e-9)}}[kind]
    fewest = sensor(**kw).echo_samples
    assert fewest == {"gaussian": 70, "box": 12}.get(kind, fewest)
    pat = ScanPattern([0.0], [[1.0, 0.0, 0.0]])
    free = scan(scene(plate(100.0)), pat, Platform.static((0, 0, 0)), sensor(**kw),
                keep_waveforms=True)
    assert len(free.waveforms[0][0]) in (fewest - 1, fewest)
    fixed = scan(scene(plate(100.0)), pat, Platform.static((0, 0, 0)),
                 sensor(samples=fewest, **kw))
    np.testing.assert_allclose(fixed.points["range"], free.points["range"], atol=1e-9)
    with pytest.raises(ParameterError, match=f"give {fewest} or more"):
        sensor(samples=fewest - 1, **kw)


def _raster():
    """13 pulses, 10° apart in azimuth (one sub-ray each with :func:`sensor`'s beam)."""
    return raster(np.arange(-60.0, 61.0, 10.0), [0.0], pulse_rate=1e4)


def test_a_scan_with_no_return_says_which_pulses_met_the_scene_and_how_bright_they_were():
    """An empty cloud was returned without a word (a scene in millimetres read as metres
    lies a thousand times farther and gives nothing). Too weak: the pulses within
    atan(20/50) = 21.8° of the boresight (5 of 13) meet the plate, the brightest (on the
    boresight) returning the link budget by hand; a Geiger-mode flash array's pixels, all
    on the plate, named as pixels; a black plate met by as many; facing away: none."""
    target = scene(plate(50.0))
    weak = sensor(pulse_energy=1e-16)
    with pytest.warns(EmptyScanWarning) as got:
        cloud = scan(target, _raster(), Platform.static((0, 0, 0)), weak)
    assert len(cloud) == 0 and len(got) == 1
    brightest = photoelectrons_by_hand(1e-16, 0.05, 50.0)
    text = str(got[0].message)
    assert "5 of 13 pulses met the scene" in text and f"returned {brightest:.3g} " in text
    assert "or its detector's false_alarm (the threshold follows it)" in text
    centre = f"{50.0 + 0.01 / 2:.4g} m away"                 # the plate's middle, x = 50.005
    assert centre in text and got[0].filename == __file__
    with pytest.warns(EmptyScanWarning, match="16 of 16 pixels met the scene, but no echo "
                                              "stood out of a Geiger-mode pixel's histogram "
                                              r"\(the brightest pixel .* or its GeigerMode's "
                                              "shots"):
        scan(target, flash(4, 4, ifov_deg=0.1), Platform.static((0, 0, 0)),
             sensor(pulse_energy=1e-22, geiger=GeigerMode(shots=10)))
    with pytest.warns(EmptyScanWarning, match=r"5 of 13 pulses met .* returned 0 photo"):
        scan(ml.Scene.from_meshes([(plate(50.0), ml.brdf.Lambertian(0.0))]), _raster(),
             Platform.static((0, 0, 0)), sensor())                      # a black plate
    with pytest.warns(EmptyScanWarning, match=f"none of the 13 pulses met the scene .*{centre}"):
        scan(target, _raster(), Platform.static((0, 0, 0), attitude_deg=(0, 0, 180)),
             sensor())


def test_an_empty_scan_resumed_from_its_folder_still_says_why(tmp_path):
    """The photoelectrons each pulse returned are kept with its chunk, so a run read back
    from its folder gives the same word as the run that made it."""
    args = (scene(plate(50.0)), _raster(), Platform.static((0, 0, 0)),
            sensor(pulse_energy=1e-16))
    for _ in range(2):
        with pytest.warns(EmptyScanWarning, match="5 of 13 pulses met the scene"):
            scan(*args, run_dir=tmp_path / "run")
    assert list((tmp_path / "run").glob("chunk_*.npz"))


def test_an_empty_scan_whose_records_cut_its_echoes_names_the_length_not_the_energy():
    """The ring of the test above, too dark to detect, and the wall behind it past an
    80-sample record: both warnings name the same length that holds the echoes (the
    empty scan's word does not ask for more pulse energy)."""
    from meshladar.errors import RecordLengthWarning
    from meshladar.scan import ScanPattern

    sc = ml.Scene.from_meshes([(plate(RING, hole=HOLE), ml.brdf.Lambertian(1e-9)),
                               (plate(WALL), ml.brdf.Lambertian(0.5))])
    with pytest.warns(MeshladarWarning) as caught:
        scan(sc, ScanPattern([0.0], [[1.0, 0.0, 0.0]]), Platform.static((0, 0, 0)),
             sensor(beam=ScanBeam(1e-2, sub_rays=64), samples=80))
    kinds = [type(w.message) for w in caught]
    assert kinds == [RecordLengthWarning, EmptyScanWarning]
    need = str(caught[0].message).split("; samples=")[1].split()[0]
    assert f"samples=80 cut the echoes" in str(caught[1].message)
    assert f"(samples={need} holds them all" in str(caught[1].message)
    assert "pulse_energy" not in str(caught[1].message)


class _NanAtNormal(ml.brdf.BRDF):
    """A user's coating that gives NaN near normal incidence (cos θ > 0.99)."""

    def projected(self, cos_theta, sin_theta):
        c = np.asarray(cos_theta, float)
        return np.where(c > 0.99, np.nan, 0.1 * c)


def test_a_coating_that_gives_nan_scans_into_a_run_folder_as_without_one(tmp_path):
    """A sub-ray's photoelectrons count where positive (as the echoes count them): a NaN
    from a user's coating reaches no chunk's numbers, so a run folder takes the chunk
    (it refused non-finite values) and gives the points of a run without one."""
    args = (ml.Scene.from_meshes([(plate(50.0), _NanAtNormal())]), _raster(),
            Platform.static((0, 0, 0)), sensor())
    plain = scan(*args)
    folder = scan(*args, run_dir=tmp_path / "run")
    assert len(plain) == 4                     # the 4 pulses off the boresight's NaN
    np.testing.assert_array_equal(folder.points, plain.points)


def test_an_empty_scan_read_from_an_older_run_folder_says_what_it_can(tmp_path):
    """Chunks made before they kept what met the scene (here: a run's chunks with it taken
    out, checksums redone) still load, not recomputed: the word then names where the
    sensor and the scene were, and no count."""
    from meshladar.io import load_result, save_result
    from meshladar.runs import chunk_digest

    args = (scene(plate(50.0)), _raster(), Platform.static((0, 0, 0)),
            sensor(pulse_energy=1e-16))
    with pytest.warns(EmptyScanWarning, match="5 of 13 pulses met"):
        scan(*args, run_dir=tmp_path / "run")
    chunks = sorted((tmp_path / "run").glob("chunk_*.npz"))
    for f in chunks:
        arrays, meta = load_result(f)
        del arrays["lit"]
        save_result(f, arrays, dict(meta, sha256=chunk_digest(arrays)))
    with pytest.warns(EmptyScanWarning, match="the chunks read from an older run folder "
                                              r"do not say more \(the sensor at"):
        scan(*args, run_dir=tmp_path / "run")
    assert all("lit" not in load_result(f)[0] for f in chunks)      # read, not made again
