"""refract.methods(), refract.builtin_scenes(), Scene.builtin_names()."""

import refract


def test_methods_are_the_registry():
    methods = refract.methods()
    ids = [m.id for m in methods]
    assert ids[0] == "reference"
    for expected in ("single", "wyman", "distance-map", "pvrr", "screen-offset", "proxy-sphere"):
        assert expected in ids
    assert len(set(ids)) == len(ids)
    wyman = next(m for m in methods if m.id == "wyman")
    assert wyman.family == "image-space"
    assert "Wyman" in wyman.paper
    assert set(wyman.backends) == {"cpu", "gpu"}
    assert "T2" in wyman.aovs and "covered" in wyman.aovs
    reference = methods[0]
    assert reference.backends == ("trace", "gpu")


def test_parameters_carry_ranges_and_defaults():
    by_id = {m.id: m for m in refract.methods()}
    spp = next(p for p in by_id["reference"].params if p.name == "spp")
    assert spp.kind == "integer"
    assert spp.minimum is not None and spp.maximum is not None
    assert spp.minimum <= int(spp.default) <= spp.maximum
    mode = next(p for p in by_id["reference"].params if p.name == "mode")
    assert mode.kind == "choice" and mode.default in mode.choices
    assert "transmission" in mode.choices and "full" in mode.choices
    for method in by_id.values():
        for p in method.params:
            if p.kind == "choice":
                assert p.default in p.choices, (method.id, p)
            else:
                assert p.minimum <= int(p.default) <= p.maximum, (method.id, p)


def test_builtin_scenes():
    names = refract.Scene.builtin_names()
    assert "sphere" in names and "engine-failures" in names
    assert [n for n, _ in refract.builtin_scenes()] == names
    assert all(description for _, description in refract.builtin_scenes())
