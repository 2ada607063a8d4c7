// The spectral functions of refract_core::spectral, line by line (Mitsuba 3's spectral
// variants: hero wavelengths from its RGB importance density, CIE 1931 to linear sRGB, Jakob and
// Hanika's sigmoid spectra, the KHR_materials_dispersion index). The uplift table lookup needs
// the table in a buffer: refract-gpu's reference.wgsl holds its twin.

const SPECTRAL_LAMBDA_MIN: f32 = 360.0;
const SPECTRAL_LAMBDA_MAX: f32 = 830.0;
const SPECTRAL_CIE_Y_NORMALIZATION: f32 = 1.0 / 106.75026;
const SPECTRAL_D65_NORMALIZATION: f32 = 1.0 / 98.99742;
// Wavelengths per sample (refract_core::spectral::WAVELENGTHS).
const SPECTRAL_WAVELENGTHS: f32 = 4.0;

// CIE_1931_XYZ (x̄, ȳ, z̄ at 360 + 5 i nm) and CIE_D65 (100 at 560 nm) are declared by the
// constants header, written from spectral/tables.rs (refract_core::spectral::wgsl_tables).

// table_position: (i0, w1) of `lambda` in the 5 nm tables; i0 < 0 outside 360–830 nm.
fn spectral_table_position(lambda: f32) -> vec2<f32> {
    if !(lambda >= SPECTRAL_LAMBDA_MIN && lambda <= SPECTRAL_LAMBDA_MAX) {
        return vec2<f32>(-1.0, 0.0);
    }
    let t = (lambda - SPECTRAL_LAMBDA_MIN) * (94.0 / (SPECTRAL_LAMBDA_MAX - SPECTRAL_LAMBDA_MIN));
    let i0 = min(u32(t), 93u);
    return vec2<f32>(f32(i0), t - f32(i0));
}

// spectral::cie_1931_xyz.
fn cie_1931_xyz(lambda: f32) -> vec3<f32> {
    let p = spectral_table_position(lambda);
    if p.x < 0.0 {
        return vec3<f32>(0.0);
    }
    let i = u32(p.x);
    let w1 = p.y;
    let w0 = 1.0 - w1;
    let a = CIE_1931_XYZ[i];
    let b = CIE_1931_XYZ[i + 1u];
    return vec3<f32>(w0 * a.x + w1 * b.x, w0 * a.y + w1 * b.y, w0 * a.z + w1 * b.z);
}

// spectral::d65.
fn cie_d65(lambda: f32) -> f32 {
    let p = spectral_table_position(lambda);
    if p.x < 0.0 {
        return 0.0;
    }
    let i = u32(p.x);
    return ((1.0 - p.y) * CIE_D65[i] + p.y * CIE_D65[i + 1u]) * SPECTRAL_D65_NORMALIZATION;
}

// spectral::cosh.
fn spectral_cosh(x: f32) -> f32 {
    let e = exp(x);
    return 0.5 * (e + 1.0 / e);
}

// spectral::sample_rgb_spectrum: (λ, 1 / p(λ)).
fn sample_rgb_spectrum(u: f32) -> vec2<f32> {
    let x = 0.8569106 - 1.827502 * u;
    let lambda = 538.0 - 0.5 * log((1.0 + x) / (1.0 - x)) * 138.88889;
    let c = spectral_cosh(0.0072 * (lambda - 538.0));
    return vec2<f32>(lambda, 253.82 * c * c);
}

// spectral::sigmoid_spectrum: Jakob and Hanika's S(λ) of coefficients `c` (of λ in nm).
fn sigmoid_spectrum(c: vec3<f32>, lambda: f32) -> f32 {
    if abs(c.z) > 3.0e38 {
        return select(0.0, 1.0, c.z > 0.0);
    }
    let x = (c.x * lambda + c.y) * lambda + c.z;
    return max(0.5 * x / sqrt(x * x + 1.0) + 0.5, 0.0);
}

// spectral::dispersive_ior: KHR_materials_dispersion's n(λ) (an infinite Abbe number: n_d).
fn dispersive_ior(ior: f32, abbe: f32, lambda: f32) -> f32 {
    if abbe > 3.0e38 {
        return ior;
    }
    return ior + (ior - 1.0) / abbe * (523655.0 / (lambda * lambda) - 1.5168);
}

// spectral::Wavelengths: four wavelengths (x is the hero) and their weights 1 / p(λ), 0 where
// terminated.
struct Wavelengths {
    lambda: vec4<f32>,
    weight: vec4<f32>,
}

// Wavelengths::sample.
fn wavelengths_sample(u: f32) -> Wavelengths {
    var w: Wavelengths;
    for (var i = 0u; i < 4u; i++) {
        var ui = u + f32(i) / SPECTRAL_WAVELENGTHS;
        if ui >= 1.0 {
            ui -= 1.0;
        }
        let s = sample_rgb_spectrum(ui);
        w.lambda[i] = s.x;
        w.weight[i] = s.y;
    }
    return w;
}

// Wavelengths::terminate_secondary, returning the result.
fn wavelengths_terminated(w: Wavelengths) -> Wavelengths {
    if w.weight.y == 0.0 {
        return w;
    }
    return Wavelengths(w.lambda, vec4<f32>(w.weight.x * SPECTRAL_WAVELENGTHS, 0.0, 0.0, 0.0));
}

// Wavelengths::to_linear_srgb: the linear sRGB estimate of spectral radiance `values`.
fn wavelengths_to_linear_srgb(w: Wavelengths, values: vec4<f32>) -> vec3<f32> {
    var xyz = vec3<f32>(0.0);
    for (var i = 0u; i < 4u; i++) {
        if w.weight[i] != 0.0 {
            xyz += cie_1931_xyz(w.lambda[i]) * (values[i] * w.weight[i]);
        }
    }
    xyz *= SPECTRAL_CIE_Y_NORMALIZATION / SPECTRAL_WAVELENGTHS;
    return vec3<f32>(
        3.240479 * xyz.x - 1.53715 * xyz.y - 0.498535 * xyz.z,
        -0.969256 * xyz.x + 1.875991 * xyz.y + 0.041556 * xyz.z,
        0.055648 * xyz.x - 0.204043 * xyz.y + 1.057311 * xyz.z,
    );
}
