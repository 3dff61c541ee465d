"""LineMod templates: the view sphere, training, the cache file round trip, matching."""

import numpy as np
import pytest

from sann.vision import linemod
from sann.vision.camera import make_pose
from sann.vision.linemod import (
    TemplateParams,
    get_templates,
    load_templates,
    match_templates,
    save_templates,
    template_key,
    template_views,
)
from sann.vision.render import render_cup

SMALL = TemplateParams(tilt_step_deg=30.0, distances_mm=(600.0,), n_patches=4)


@pytest.fixture(scope="module")
def small_set():
    return get_templates(SMALL)


def test_views_cover_every_axis_direction():
    step = 15.0
    rots = template_views(step)
    assert len(rots) * 3 >= 300  # three distances make the >= 300 templates of the spec
    assert np.allclose(rots @ rots.transpose(0, 2, 1), np.eye(3), atol=1e-12)
    axes = rots[:, :, 2]
    rng = np.random.default_rng(0)
    probe = rng.normal(size=(2000, 3))
    probe /= np.linalg.norm(probe, axis=1, keepdims=True)
    worst = np.degrees(np.arccos(np.clip((probe @ axes.T).max(axis=1), -1, 1))).max()
    assert worst < step  # every direction within one step of a template's axis


def test_training_records_per_template_geometry(small_set):
    n = len(small_set)
    assert n == len(template_views(SMALL.tilt_step_deg)) == small_set.detector.numTemplates()
    for i in range(n):
        c, d = small_set.color_features[i], small_set.depth_features[i]
        assert c.shape[1] == d.shape[1] == 3 and len(c) >= 20 and len(d) >= 20
        assert np.all(c[:, :2] <= small_set.sizes[i]) and np.all(d[:, :2] <= small_set.sizes[i])
        assert set(small_set.color_patches[i].tolist()) == set(range(SMALL.n_patches))
        # Depth features lie on the cup, within its half-diagonal (74 mm) of the centre, and
        # the surface the camera sees is on average in front of the centre.
        off = small_set.depth_offsets[i]
        assert np.all(np.isfinite(off)) and np.all(np.abs(off) < 75.0) and off.mean() > 0


def test_save_load_round_trip(small_set, tmp_path):
    path = tmp_path / "templates.npz"
    save_templates(small_set, path)
    assert [p.name for p in tmp_path.iterdir()] == ["templates.npz"]  # no temp file left
    loaded = load_templates(path)
    assert loaded.params == small_set.params and loaded.key == small_set.key
    for name in ("rotations", "distances", "origins", "sizes"):
        assert np.array_equal(getattr(loaded, name), getattr(small_set, name))
    for name in ("color_features", "depth_features", "color_patches", "depth_patches"):
        for a, b in zip(getattr(loaded, name), getattr(small_set, name), strict=True):
            assert np.array_equal(a, b)
    res = render_cup(make_pose(small_set.rotations[7], np.array([30.0, -20.0, 600.0])))
    m0 = match_templates(small_set, res.rgb, res.depth_mm, 80.0)
    m1 = match_templates(loaded, res.rgb, res.depth_mm, 80.0)
    assert len(m0) > 0
    assert np.array_equal(m0.template_id, m1.template_id)
    assert np.array_equal(m0.similarity, m1.similarity) and np.array_equal(m0.x, m1.x)


def test_a_rendered_view_matches_its_own_template(small_set):
    tid = 12
    res = render_cup(make_pose(small_set.rotations[tid], np.array([0.0, 0.0, 600.0])))
    m = match_templates(small_set, res.rgb, res.depth_mm, 90.0)
    best = int(np.argmax(m.similarity))
    assert m.template_id[best] == tid and m.similarity[best] == pytest.approx(100.0)
    # Matches are scored on LineMod's T = 5 grid and the spread makes every corner up to T - 1
    # pixels above-left of the true one score fully, so the corner is found to within T - 1.
    lag = small_set.origins[tid] - np.array([m.x[best], m.y[best]])
    assert np.all((lag >= 0) & (lag < linemod.T_LEVEL0))


def test_cache_is_keyed_and_reused(monkeypatch, tmp_path):
    monkeypatch.setenv("SANN_CACHE", str(tmp_path))
    monkeypatch.setattr(linemod, "_MEMORY", {})
    params = TemplateParams(tilt_step_deg=60.0, distances_mm=(650.0,), n_patches=3)
    first = get_templates(params)
    files = list(tmp_path.glob("linemod-*.npz"))
    assert [f.name for f in files] == [f"linemod-{first.key}.npz"]
    monkeypatch.setattr(linemod, "_MEMORY", {})
    monkeypatch.setattr(linemod, "train_templates", lambda *a: pytest.fail("retrained"))
    second = get_templates(params)
    assert second.key == first.key and len(second) == len(first)
    assert template_key(params) != template_key(TemplateParams(60.0, (650.0,), 4))


def test_bad_parameters_and_frames_are_rejected(small_set):
    with pytest.raises(ValueError):
        TemplateParams(tilt_step_deg=0.5)
    with pytest.raises(ValueError):
        TemplateParams(distances_mm=())
    with pytest.raises(ValueError):
        TemplateParams(n_patches=2)
    with pytest.raises(ValueError):
        match_templates(small_set, np.zeros((480, 640), np.uint8), np.zeros((480, 640), np.uint16))
    with pytest.raises(ValueError):
        match_templates(small_set, np.zeros((480, 640, 3), np.uint8), np.zeros((480, 640)))
    with pytest.raises(FileNotFoundError):
        load_templates("/nonexistent/templates.npz")


def test_patch_figure_shows_the_patches_detection_uses(small_set):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sann.vision.evaluate import draw_patches

    fig, (a, b) = plt.subplots(1, 2)
    labels = draw_patches(a, b, small_set, 5, "color")
    assert np.array_equal(labels, small_set.color_patches[5])
    assert len(a.collections) == 1 and len(b.collections) == 1
    plt.close(fig)
