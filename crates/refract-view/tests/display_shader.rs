//! The viewer's WGSL is parsed and validated by naga inside `cargo test` (no adapter needed),
//! like every shader of the GPU backend, and has the entry points the viewer asks for: the
//! display of CPU-tonemapped pixels and the display of a GPU frame's colour buffer.

#[test]
fn the_display_shaders_validate_and_have_their_entry_points() {
    for (name, source) in [
        ("display.wgsl", include_str!("../shaders/display.wgsl")),
        (
            "display_frame.wgsl",
            include_str!("../shaders/display_frame.wgsl"),
        ),
    ] {
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|err| panic!("{name}: {}", err.emit_to_string(source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|err| panic!("{name}: {}", err.emit_to_string(source)));
        let entry_points: Vec<(&str, naga::ShaderStage)> = module
            .entry_points
            .iter()
            .map(|e| (e.name.as_str(), e.stage))
            .collect();
        assert_eq!(
            entry_points,
            [
                ("vs", naga::ShaderStage::Vertex),
                ("fs", naga::ShaderStage::Fragment)
            ],
            "{name}"
        );
    }
}
