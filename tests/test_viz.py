"""Offline meshcat scenes (recorder, embedding, builders) and the architecture diagram."""

from __future__ import annotations

import base64
import html

import matplotlib
import meshcat.geometry as g
import meshcat.transformations as tf
import numpy as np
import pytest
import umsgpack

matplotlib.use("Agg")

from sann.nets import DeepNet, ShallowNet  # noqa: E402
from sann.tasks.blocks import generate_scene, scene_from_blocks  # noqa: E402
from sann.viz import embed  # noqa: E402
from sann.viz.diagrams import architecture_figure, linear_widths  # noqa: E402
from sann.viz.meshcat_scenes import (  # noqa: E402
    blocks_scene,
    cups_scene,
    parking_spot,
    plan_animation,
    rgb_int,
)


def unpacked(scene: embed.Scene) -> list[dict]:
    return [umsgpack.unpackb(c) for c in scene.recorder.commands()]


def paths(scene: embed.Scene, kind: str) -> list[str]:
    return [c["path"] for c in unpacked(scene) if c["type"] == kind]


# --------------------------------------------------------------------------- recorder


def test_recorder_keeps_the_last_object_and_resets_its_properties() -> None:
    scene = embed.Scene()
    scene.vis["a"].set_object(g.Box([1, 1, 1]))
    scene.vis["a"].set_property("visible", False)
    scene.vis["a"].set_object(g.Sphere(0.5))
    objects = [c for c in unpacked(scene) if c["type"] == "set_object"]
    assert len(objects) == 1
    assert objects[0]["object"]["geometries"][0]["type"] == "SphereGeometry"
    assert paths(scene, "set_property") == []


def test_recorder_delete_drops_a_subtree_and_root_delete_clears_all() -> None:
    scene = embed.Scene()
    scene.vis["a/b"].set_object(g.Box([1, 1, 1]))
    scene.vis["c"].set_object(g.Box([1, 1, 1]))
    scene.vis["a"].delete()
    assert paths(scene, "set_object") == ["/meshcat/c"]
    scene.vis["/"].delete()
    assert scene.recorder.commands() == []


def test_recorder_replays_a_transform_after_its_object() -> None:
    scene = embed.Scene()
    scene.vis["a"].set_transform(tf.translation_matrix([1, 2, 3]))
    scene.vis["a"].set_object(g.Box([1, 1, 1]))
    kinds = [c["type"] for c in unpacked(scene)]
    assert kinds == ["set_object", "set_transform"]


def test_static_page_is_self_contained_or_uses_the_shared_script() -> None:
    scene = embed.Scene()
    scene.vis["a"].set_object(g.Box([1, 1, 1]))
    inline = scene.static_html()
    assert embed.viewer_js_path().read_text(encoding="utf-8")[:200] in inline
    assert "http://" not in inline.split("<script>")[0]
    shared = scene.static_html(js_url="_static/meshcat/main.min.js")
    assert '<script src="_static/meshcat/main.min.js"></script>' in shared
    assert len(shared) < 10_000
    packed = scene.recorder.commands()[0]
    assert base64.b64encode(packed).decode() in shared


def test_iframe_escapes_the_page_and_rejects_a_bad_height() -> None:
    page = '<p class="x">a & b</p>'
    frame = embed.iframe(page, height=300)
    assert 'srcdoc="' + html.escape(page, quote=True) + '"' in frame
    assert "height:300px" in frame
    with pytest.raises(ValueError):
        embed.iframe(page, height=0)


def test_mode_resolution(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(embed.MODE_ENV, raising=False)
    monkeypatch.delenv("JPY_SESSION_NAME", raising=False)
    assert embed.resolve_mode() == "static"
    monkeypatch.setenv("JPY_SESSION_NAME", "book/blocks.md")
    assert embed.resolve_mode() == "live"
    monkeypatch.setenv(embed.MODE_ENV, "static")
    assert embed.resolve_mode() == "static"
    assert embed.resolve_mode("live") == "live"
    with pytest.raises(ValueError):
        embed.resolve_mode("3d")
    monkeypatch.setenv(embed.MODE_ENV, "bogus")
    with pytest.raises(ValueError):
        embed.resolve_mode()
    with pytest.raises(ValueError):
        embed.Scene(mode="bogus")


def test_repr_html_is_a_static_iframe_outside_jupyterlab(monkeypatch) -> None:
    monkeypatch.setenv(embed.MODE_ENV, "static")
    monkeypatch.setenv(embed.JS_URL_ENV, "_static/meshcat/main.min.js")
    scene = embed.Scene(height=250)
    scene.vis["a"].set_object(g.Box([1, 1, 1]))
    out = scene._repr_html_()
    assert out.startswith('<div class="sann-scene"') and "sann-scene-frame" in out
    assert "_static/meshcat/main.min.js" in out


def test_unknown_command_is_refused() -> None:
    class Odd:
        def lower(self) -> dict:
            return {"type": "capture_image", "path": ""}

    with pytest.raises(ValueError, match="capture_image"):
        embed.SceneRecorder().send(Odd())


# --------------------------------------------------------------------------- builders


def test_rgb_int() -> None:
    assert rgb_int((255, 0, 16)) == 0xFF0010
    with pytest.raises(ValueError):
        rgb_int((256, 0, 0))


def test_blocks_scene_draws_every_block_at_its_centre_in_metres() -> None:
    scene = generate_scene("C3", 9, rng=4)
    view = blocks_scene(scene, highlight=[scene.names[0]])
    objects = paths(view, "set_object")
    for name in scene.names:
        assert f"/meshcat/world/blocks/{name}" in objects
    assert f"/meshcat/world/blocks/{scene.names[0]}/halo" in objects
    transforms = {c["path"]: c["matrix"] for c in unpacked(view) if c["type"] == "set_transform"}
    matrix = np.array(transforms[f"/meshcat/world/blocks/{scene.names[1]}"]).reshape(4, 4).T
    np.testing.assert_allclose(matrix[:3, 3], scene.centre[1] * 0.01, atol=1e-6)


def test_blocks_scene_rejects_other_objects() -> None:
    with pytest.raises(TypeError):
        blocks_scene({"blocks": []})


def test_plan_animation_moves_the_blocks_in_plan_order() -> None:
    scene = scene_from_blocks([("A", 10, (50, 50, 5), 1), ("B", 10, (50, 50, 15), 2),
                               ("C", 5, (80, 80, 2.5), 3)])
    view = plan_animation(scene, ["B", "A"])
    animation = [c for c in unpacked(view) if c["type"] == "set_animation"]
    assert len(animation) == 1
    clips = {a["path"]: a["clip"] for a in animation[0]["animations"]}
    assert set(clips) == {"/meshcat/world/blocks/A", "/meshcat/world/blocks/B"}

    def leaves(name: str) -> float:
        track = next(t for t in clips[f"/meshcat/world/blocks/{name}"]["tracks"]
                     if t["name"] == ".position")
        start = track["keys"][0]["value"]
        return next(k["time"] for k in track["keys"] if k["value"] != start)

    assert leaves("B") < leaves("A")
    last = next(t for t in clips["/meshcat/world/blocks/A"]["tracks"] if t["name"] == ".position")
    np.testing.assert_allclose(last["keys"][-1]["value"][:2], parking_spot(1)[:2] * 0.01)
    assert "/meshcat/world/blocks/A/halo" in paths(view, "set_object")  # the target


@pytest.mark.parametrize("plan", [[], ["A", "A"], ["Q"]])
def test_plan_animation_rejects_bad_plans(plan: list[str]) -> None:
    scene = scene_from_blocks([("A", 10, (50, 50, 5), 1)])
    with pytest.raises(ValueError):
        plan_animation(scene, plan)


class _Tetra:
    vertices = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], dtype=float)
    faces = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])


def test_cups_scene_true_and_estimated_poses() -> None:
    poses = np.stack([tf.translation_matrix([100.0 * i, 0, 60]) for i in range(3)])
    view = cups_scene(poses, _Tetra(), estimated=poses[:2])
    objects = paths(view, "set_object")
    assert sum("/cups/true/" in p for p in objects) == 3
    assert sum("/cups/estimated/" in p for p in objects) == 2
    transforms = {c["path"]: c["matrix"] for c in unpacked(view) if c["type"] == "set_transform"}
    matrix = np.array(transforms["/meshcat/world/cups/true/cup2"]).reshape(4, 4).T
    np.testing.assert_allclose(matrix[:3, 3], [0.2, 0.0, 0.06])


def test_cups_scene_rejects_bad_input() -> None:
    with pytest.raises(ValueError):
        cups_scene(np.zeros((3, 3)), _Tetra())
    with pytest.raises(ValueError):
        cups_scene(np.stack([np.eye(4)]), object())


# --------------------------------------------------------------------------- diagram


def test_linear_widths_follow_the_forward_pass() -> None:
    assert linear_widths(ShallowNet(15)) == [15, 5, 2]
    assert linear_widths(DeepNet(131, hidden=(64, 32, 16))) == [131, 64, 32, 16, 2]


def test_architecture_figure_checks_the_fused_input_width() -> None:
    fig = architecture_figure([15, 5, 2], n_features=14)
    assert fig.axes
    with pytest.raises(ValueError, match="N \\+ 1"):
        architecture_figure([14, 5, 2], n_features=14)
    with pytest.raises(ValueError):
        architecture_figure([15], n_features=14)
