"""refract.metrics and refract.error_maps."""

import json

import numpy as np
import pytest

import refract


@pytest.fixture(scope="module")
def frames():
    scene = refract.Scene.load("sphere")
    reference = scene.render("reference", res=(64, 64), aovs=True)
    return scene, reference


def test_metrics_have_every_field_of_metrics_json(frames, tmp_path):
    scene, reference = frames
    wyman = refract.metrics(scene.render("wyman", res=(64, 64), aovs=True), reference)
    single = refract.metrics(scene.render("single", res=(64, 64), aovs=True), reference)
    records = refract.compare("sphere", methods=["wyman"], res=64, frames=1, out=tmp_path)
    written = json.loads((tmp_path / "metrics.json").read_text())
    assert set(wyman) == set(records[1]) == set(written[1])
    assert wyman["method"] == "wyman" and wyman["backend"] == "cpu" and wyman["scene"] == "sphere"
    assert 0 < wyman["flip_mean"] < 1
    assert wyman["refractor_pixels"] == records[1]["refractor_pixels"] > 100
    # The same frame, the same metrics as refract compare's (timing aside).
    for field in ("flip_mean", "rmse", "t2_angle_deg_mean", "p2_error_rel_mean"):
        assert wyman[field] == pytest.approx(records[1][field], rel=1e-9), field
    # Wyman's second interface is closer to the truth than one interface (Wyman 2005a §4).
    assert wyman["t2_angle_deg_mean"] < single["t2_angle_deg_mean"]
    # Fields a method does not have are None.
    assert wyman["zoom_share"] is None


def test_metrics_of_the_reference_itself_are_zero(frames):
    scene, reference = frames
    again = scene.render("reference", res=(64, 64), aovs=True)
    m = refract.metrics(again, reference)
    assert m["flip_mean"] == 0 and m["rmse"] == 0


def test_error_maps(frames):
    scene, reference = frames
    frame = scene.render("wyman", res=(64, 64), aovs=True)
    maps = refract.error_maps(frame, reference)
    assert set(maps) == {"flip", "t2_deg", "p2_rel"}
    for values in maps.values():
        assert values.shape == (64, 64) and values.dtype == np.float32
    covered = reference.aov("covered")
    m = refract.metrics(frame, reference)
    assert float(np.mean(maps["flip"][covered])) == pytest.approx(m["flip_mean"], rel=1e-5)
    assert np.isnan(maps["t2_deg"][~covered]).all()


def test_metrics_refuse_frames_that_cannot_be_compared(frames, tmp_path):
    scene, reference = frames
    with pytest.raises(ValueError, match="aovs=True"):
        refract.metrics(scene.render("wyman", res=(64, 64)), reference)
    with pytest.raises(ValueError, match="camera or resolution"):
        refract.metrics(scene.render("wyman", res=(32, 32), aovs=True), reference)
    frame = scene.render("wyman", res=(64, 64), aovs=True)
    with pytest.raises(ValueError, match="must be the reference"):
        refract.metrics(reference, frame)
    frame.save(tmp_path / "f.exr")
    with pytest.raises(ValueError, match="read from a file"):
        refract.metrics(refract.Frame.load(tmp_path / "f.exr"), reference)
