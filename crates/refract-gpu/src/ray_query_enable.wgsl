// The ray-query reference module's enable directive (wgpu's EXPERIMENTAL_RAY_QUERY; issue 32).
// ShaderModule::source hoists every file's `enable` lines above all declarations, as WGSL
// requires.
enable wgpu_ray_query;
