"""refract.Scene: loading, errors, the camera."""

import math

import pytest

import refract


def test_load_builtin_and_ior(sphere):
    assert sphere.name == "sphere"
    assert sphere.ior == pytest.approx(1.5)
    glass = refract.Scene.load("sphere", ior=1.2)
    assert glass.ior == pytest.approx(1.2)
    assert "sphere" in repr(glass)
    assert sphere.roughness == [0.0]
    assert refract.Scene.load("rough-glass").roughness == pytest.approx([0.0, 0.1, 0.3, 0.6])
    assert sphere.abbe == [math.inf]
    assert refract.Scene.load("prism").abbe == pytest.approx([30.0])


def test_bad_inputs_raise_the_cli_messages(tmp_path):
    with pytest.raises(ValueError, match="unknown scene `no-such-scene`"):
        refract.Scene.load("no-such-scene")
    with pytest.raises(FileNotFoundError, match="missing.toml: cannot read the scene file"):
        refract.Scene.load(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text('[refractor]\nmesh = "nowhere.obj"\n')
    with pytest.raises(FileNotFoundError, match="nowhere.obj"):
        refract.Scene.load(bad)
    with pytest.raises(ValueError, match="ior = 0"):
        refract.Scene.load("sphere", ior=0.0)
    broken = tmp_path / "broken.toml"
    broken.write_text("[refractor\n")
    with pytest.raises(ValueError, match="broken.toml"):
        refract.Scene.load(broken)


def test_camera_is_readable_and_settable():
    scene = refract.Scene.load("sphere")
    eye, target = scene.eye, scene.target
    assert len(eye) == 3 and len(target) == 3
    distance = math.dist(eye, target)
    assert distance > 0
    scene.eye = (distance, 0.0, 0.0)
    scene.target = (0.0, 0.0, 0.0)
    scene.fov = 30.0
    assert scene.eye == (pytest.approx(distance), 0.0, 0.0)
    assert scene.fov == pytest.approx(30.0)
    # An orbit: the image changes with the camera.
    first = scene.render("single", res=(32, 32)).color.copy()
    scene.eye = (0.0, 0.5, distance)
    second = scene.render("single", res=(32, 32)).color
    assert not (first == second).all()


def test_bad_camera_values_are_refused_and_leave_the_camera():
    scene = refract.Scene.load("sphere")
    before = (scene.eye, scene.up, scene.fov)
    with pytest.raises(ValueError, match="fov"):
        scene.fov = 180.0
    with pytest.raises(ValueError, match="fov"):
        scene.fov = 0.0
    with pytest.raises(ValueError, match="eye"):
        scene.eye = (float("nan"), 0.0, 0.0)
    with pytest.raises(ValueError, match="camera"):
        scene.up = tuple(t - e for t, e in zip(scene.target, scene.eye))
    with pytest.raises(ValueError, match="camera"):
        scene.eye = scene.target
    assert (scene.eye, scene.up, scene.fov) == before


def test_file_names_that_are_not_utf8_load(tmp_path):
    # Issue 54 #12: before, the name was decoded lossily and the file "did not exist".
    import os

    path = os.path.join(os.fsdecode(bytes(tmp_path)), os.fsdecode(b"glass\xff.toml"))
    with open(path, "w") as f:
        f.write('[refractor]\nmesh = "builtin:sphere"\n')
    assert refract.Scene.load(path).name == "glass\ufffd"
    records = refract.compare(path, methods="single", res=8, frames=1, out=tmp_path / "out")
    assert [r["method"] for r in records] == ["reference", "single"]
