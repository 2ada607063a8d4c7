//! The WGSL library of `refract_core::wgsl` parses and validates with naga (no GPU needed), alone
//! and in front of a shader that calls it, and defines the functions its docs name.

fn validate(source: &str) {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|err| panic!("{}", err.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|err| panic!("{}", err.emit_to_string(source)));
}

#[test]
fn the_library_validates_alone_and_in_a_shader() {
    let library = refract_core::wgsl::library();
    validate(&library);
    for name in [
        "fn robust_normalize",
        "fn refract_dir",
        "fn reflect_dir",
        "fn face_forward_shading_normal",
        "fn angle_between",
        "fn approximate_distance",
        "fn exit_normal_outside_silhouette",
        "fn refract_exit",
        "fn fresnel_dielectric",
        "fn direction_to_latlong",
        "fn procedural_radiance",
    ] {
        assert!(library.contains(name), "{name}");
    }
    validate(&format!(
        "{library}\n@group(0) @binding(0) var<storage, read_write> out: array<vec4<f32>>;\n\
         @compute @workgroup_size(1)\nfn main() {{\n\
         let t1 = refract_dir(vec3<f32>(0.0, -1.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), 1.0 / 1.5);\n\
         out[0] = vec4<f32>(procedural_radiance(t1), 1.0);\n}}\n"
    ));
}
