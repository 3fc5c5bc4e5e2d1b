"""The Python module against physics, linear algebra and the other engine (python/README.md).

Run by CTest (label python) with PYTHONPATH at build/<kind>/python and SSSLAB_SOURCE_DIR at the
source tree; Monte Carlo checks are z-tests with fixed seeds.
"""
import math
import os
import threading
import time

import numpy as np
import pytest

import ssslab

SOURCE = os.environ.get("SSSLAB_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
Z = 4.0  # |z| bound of the z-tests (two-sided p ~ 6e-5 each)


def slab():
    # Albedo 0.9, g 0.8, eta 1.4 on a 0.1 cm slab: reflection and transmission both large.
    return ssslab.Medium(sigma_a_per_cm=1.0, sigma_s_per_cm=9.0, g=0.8, eta=1.4,
                         thickness_cm=0.1, name="slab")


def test_materials_and_media():
    assert "Skin1" in ssslab.materials()
    skin = ssslab.material("skin1")  # case-insensitive
    assert skin.name == "Skin1"
    assert skin.sigma_a_per_cm.shape == (3,)
    # mfp = 1 / (sigma_a + sigma_s (1 - g)), per channel.
    expected = 1.0 / (skin.sigma_a_per_cm + skin.sigma_s_per_cm * (1.0 - skin.g))
    np.testing.assert_allclose(skin.mfp_cm, expected, rtol=1e-15)
    with pytest.raises(ValueError, match='did you mean "Skin1"'):
        ssslab.material("Skinn1")
    with pytest.raises(ValueError, match="g must be in"):
        ssslab.Medium(sigma_a_per_cm=1, sigma_s_per_cm=1, g=2)
    with pytest.raises(ValueError, match="three"):
        ssslab.Medium(sigma_a_per_cm=[1, 2], sigma_s_per_cm=1)


def test_mcml_against_the_path_tracer():
    # Two independent engines on the same slab: total diffuse reflectance per channel within
    # their combined standard error; every bin's SE positive where the bin has weight.
    m = slab()
    mc = ssslab.mcml_profile(m, photons=20000, seed=3, nr=20, dr_cm=0.01)
    vp, single = ssslab.pencil_profile(m, paths=20000, seed=4, nr=20, dr_cm=0.01)
    assert mc.rd_per_cm2.shape == (3, 20) and vp.rd_per_cm2.shape == (3, 20)
    np.testing.assert_allclose(mc.r_cm, (np.arange(20) + 0.5) * 0.01)
    assert np.all(mc.se_per_cm2[mc.rd_per_cm2 > 0] > 0)
    z = (mc.rd_total - vp.rd_total) / np.hypot(mc.rd_total_se, vp.rd_total_se)
    assert np.all(np.abs(z) < Z), z
    # The single-scattering part is a part.
    assert np.all(single.rd_total <= vp.rd_total)
    # Specular reflection at normal incidence: ((1.4 - 1) / (1.4 + 1))^2.
    np.testing.assert_allclose(mc.rsp, (0.4 / 2.4) ** 2, rtol=1e-12)


def test_mcml_is_deterministic_for_any_thread_count():
    m = slab()
    a = ssslab.mcml_profile(m, photons=5000, seed=7, threads=1, nr=10, dr_cm=0.02)
    b = ssslab.mcml_profile(m, photons=5000, seed=7, threads=2, nr=10, dr_cm=0.02)
    np.testing.assert_array_equal(a.rd_per_cm2, b.rd_per_cm2)
    np.testing.assert_array_equal(a.se_per_cm2, b.se_per_cm2)
    c = ssslab.mcml_profile(m, photons=5000, seed=8, threads=1, nr=10, dr_cm=0.02)
    assert not np.array_equal(a.rd_per_cm2, c.rd_per_cm2)


def test_the_engines_release_the_gil():
    # While an engine runs in a thread, Python code runs beside it: with the GIL held, the loop
    # below would not advance until the run ended.
    m = slab()
    done = threading.Event()

    def work():
        ssslab.mcml_profile(m, photons=400000, seed=1, threads=1, nr=10, dr_cm=0.02)
        done.set()

    t = threading.Thread(target=work)
    ticks = 0
    start = time.monotonic()
    t.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    t.join()
    elapsed = time.monotonic() - start
    assert elapsed > 0.05, "the run was too short to tell"
    assert ticks > 10, (ticks, elapsed)


def test_diffusion_profiles_integrate_to_their_totals():
    # 2 pi int R_d r dr by an independent rule (trapezoid in ln r, r from 1e-7 to 1e3 mfp) equals
    # each model's own R_dr (closed forms for the dipoles).
    m = ssslab.material("Marble")
    mfp = float(np.max(m.mfp_cm))
    r = np.geomspace(1e-7 * mfp, 1e3 * mfp, 20001)
    for model in ["dipole", "better-dipole"]:
        rd, total = ssslab.diffusion_profile(model, m, r)
        assert rd.shape == (3, r.size)
        integral = np.trapz(2 * math.pi * rd * r * r, np.log(r), axis=1)
        np.testing.assert_allclose(integral, total, rtol=1e-4, err_msg=model)
    # Annulus means lie between the profile's values at the annulus's ends (it decreases).
    edges = np.linspace(0.01, 0.2, 11)
    point, _ = ssslab.diffusion_profile("dipole", m, edges)
    mean, _ = ssslab.diffusion_profile("dipole", m, edges, annulus=True)
    assert np.all(np.isnan(mean[:, -1]))
    assert np.all(mean[:, :-1] <= point[:, :-1]) and np.all(mean[:, :-1] >= point[:, 1:])
    with pytest.raises(ValueError, match="dipole"):
        ssslab.diffusion_profile("nonesuch", m, r)


def test_a_profile_file_is_a_model_with_parameters_per_channel():
    # experiments/bssrdf/dipole.toml, named by its path, equals the built-in dipole; its
    # Multiplier set per channel scales the channels; a value outside its range is refused.
    m = ssslab.material("Skin1")
    r = np.geomspace(1e-4, 1.0, 50)
    path = os.path.join(SOURCE, "experiments", "bssrdf", "dipole.toml")
    want, want_total = ssslab.diffusion_profile("dipole", m, r)
    got, total = ssslab.diffusion_profile(path, m, r)
    np.testing.assert_allclose(got, want, rtol=1e-12)
    np.testing.assert_allclose(total, want_total, rtol=1e-12)
    scaled, _ = ssslab.diffusion_profile(path, m, r, parameters={"Multiplier": [1.0, 2.0, 0.5]})
    np.testing.assert_allclose(scaled, want * np.array([[1.0], [2.0], [0.5]]), rtol=1e-12)
    with pytest.raises(ValueError, match="outside"):
        ssslab.diffusion_profile(path, m, r, parameters={"Multiplier": 11.0})
    with pytest.raises(ValueError, match="no parameter"):
        ssslab.diffusion_profile(path, m, r, parameters={"Gain": 1.0})
    with pytest.raises(ValueError, match="no profile file"):
        ssslab.diffusion_profile("nonesuch.toml", m, r)


def test_kernel_scores():
    p = ssslab.mcml_profile(ssslab.material("Skin1"), photons=20000, seed=1)
    assert "svd" in ssslab.kernel_models() and "preintegration" in ssslab.kernel_models()
    svd = ssslab.score_kernel(p, "svd:rank=1", channel=0)
    pre = ssslab.score_kernel(p, "preintegration", channel=0)
    # Eckart-Young: the truncated SVD is the best rank-1 approximation in the Frobenius norm.
    assert svd["rms"] <= pre["rms"]
    # Pre-integration holds the kernel's energy (unit L1) exactly [Freude14 Eq. 5.17].
    assert pre["l1_error"] < 1e-12
    assert pre["factors"].shape == (1, pre["n"]) and pre["signs"].tolist() == [1.0]
    np.testing.assert_allclose(2 * pre["factors"].sum(), 1.0, rtol=1e-12)
    svd3 = ssslab.score_kernel(p, "svd:rank=3", channel=0)
    assert svd3["factors"].shape[0] == 3 and svd3["rms"] < svd["rms"]
    with pytest.raises(ValueError, match="unknown model"):
        ssslab.score_kernel(p, "nonesuch", channel=0)
    with pytest.raises(ValueError, match="channel"):
        ssslab.score_kernel(p, "svd:rank=1", channel=3)


def test_render_layers(tmp_path):
    scene = os.path.join(SOURCE, "experiments", "scenes", "skin.toml")
    img = ssslab.render(scene, spp=3, width=16, height=12, threads=1)
    for layer in ["radiance", "radiance.stderr", "subsurface", "specular"]:
        assert img[layer].shape == (12, 16, 3), layer
        assert np.all(np.isfinite(img[layer])) and np.all(img[layer] >= 0), layer
    assert img["spp"] == 3 and img["seconds"] > 0


def test_bad_files_raise_located_input_errors(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[camera]\nposition = [0, 0, 1]\nfov_deg = "wide"\n')
    with pytest.raises(ssslab.InputError) as e:
        ssslab.render(str(bad))
    assert "bad.toml:" in str(e.value)
    assert isinstance(e.value, ValueError)
    cfg = tmp_path / "exp.toml"
    cfg.write_text('[experiment]\nname = "x"\n[mcml]\nphotons = -5\n')
    with pytest.raises(ssslab.InputError) as e:
        ssslab.run_experiment(str(cfg), results=str(tmp_path / "results"))
    assert "exp.toml:4" in str(e.value), str(e.value)
    assert not (tmp_path / "results" / "x").exists()


def test_run_experiment(tmp_path):
    cfg = tmp_path / "tiny.toml"
    cfg.write_text('[experiment]\nname = "tiny"\nseed = 1\n'
                   '[materials]\npresets = ["Skin1"]\n'
                   '[mcml]\nphotons = 4000\n[outputs.profiles]\nunit = "mm"\n')
    r = ssslab.run_experiment(str(cfg), results=str(tmp_path / "results"), threads=1)
    assert r["computed"] > 0 and r["reused"] == 0
    assert os.path.isdir(r["directory"])
    assert r["metrics"], "an experiment has metrics"
    for name, (value, se) in r["metrics"].items():
        assert math.isfinite(value) and se >= 0, name
    again = ssslab.run_experiment(str(cfg), results=str(tmp_path / "results"), threads=1)
    assert again["computed"] == 0 and again["reused"] == r["computed"]
    assert again["metrics"] == r["metrics"]


def test_the_readme_example_runs_as_written(tmp_path, monkeypatch):
    # The README's Python example, taken from the README, run in a scratch directory.
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    text = open(os.path.join(SOURCE, "README.md")).read()
    start = text.index("### From Python")
    block = text[text.index("```python\n", start) + len("```python\n"):]
    block = block[:block.index("```")]
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), {})
    assert (tmp_path / "skin_profile.png").stat().st_size > 1000
