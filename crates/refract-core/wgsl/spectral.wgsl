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

// CIE 1931 2° (x̄, ȳ, z̄) at 360 + 5 i nm (spectral/tables.rs).
const CIE_1931_XYZ = array<vec3<f32>, 95>(
    vec3<f32>(0.0001299, 3.917e-06, 0.0006061),
    vec3<f32>(0.0002321, 6.965e-06, 0.001086),
    vec3<f32>(0.0004149, 1.239e-05, 0.001946),
    vec3<f32>(0.0007416, 2.202e-05, 0.003486),
    vec3<f32>(0.001368, 3.9e-05, 0.006450001),
    vec3<f32>(0.002236, 6.4e-05, 0.01054999),
    vec3<f32>(0.004243, 0.00012, 0.02005001),
    vec3<f32>(0.00765, 0.000217, 0.03621),
    vec3<f32>(0.01431, 0.000396, 0.06785001),
    vec3<f32>(0.02319, 0.00064, 0.1102),
    vec3<f32>(0.04351, 0.00121, 0.2074),
    vec3<f32>(0.07763, 0.00218, 0.3713),
    vec3<f32>(0.13438, 0.004, 0.6456),
    vec3<f32>(0.21477, 0.0073, 1.0390501),
    vec3<f32>(0.2839, 0.0116, 1.3856),
    vec3<f32>(0.3285, 0.01684, 1.62296),
    vec3<f32>(0.34828, 0.023, 1.74706),
    vec3<f32>(0.34806, 0.0298, 1.7826),
    vec3<f32>(0.3362, 0.038, 1.77211),
    vec3<f32>(0.3187, 0.048, 1.7441),
    vec3<f32>(0.2908, 0.06, 1.6692),
    vec3<f32>(0.2511, 0.0739, 1.5281),
    vec3<f32>(0.19536, 0.09098, 1.28764),
    vec3<f32>(0.1421, 0.1126, 1.0419),
    vec3<f32>(0.09564, 0.13902, 0.8129501),
    vec3<f32>(0.05795001, 0.1693, 0.6162),
    vec3<f32>(0.03201, 0.20802, 0.46518),
    vec3<f32>(0.0147, 0.2586, 0.3533),
    vec3<f32>(0.0049, 0.323, 0.272),
    vec3<f32>(0.0024, 0.4073, 0.2123),
    vec3<f32>(0.0093, 0.503, 0.1582),
    vec3<f32>(0.0291, 0.6082, 0.1117),
    vec3<f32>(0.06327, 0.71, 0.07824999),
    vec3<f32>(0.1096, 0.7932, 0.05725001),
    vec3<f32>(0.1655, 0.862, 0.04216),
    vec3<f32>(0.2257499, 0.9148501, 0.02984),
    vec3<f32>(0.2904, 0.954, 0.0203),
    vec3<f32>(0.3597, 0.9803, 0.0134),
    vec3<f32>(0.4334499, 0.9949501, 0.008749999),
    vec3<f32>(0.5120501, 1.0, 0.005749999),
    vec3<f32>(0.5945, 0.995, 0.0039),
    vec3<f32>(0.6784, 0.9786, 0.002749999),
    vec3<f32>(0.7621, 0.952, 0.0021),
    vec3<f32>(0.8425, 0.9154, 0.0018),
    vec3<f32>(0.9163, 0.87, 0.001650001),
    vec3<f32>(0.9786, 0.8163, 0.0014),
    vec3<f32>(1.0263, 0.757, 0.0011),
    vec3<f32>(1.0567, 0.6949, 0.001),
    vec3<f32>(1.0622, 0.631, 0.0008),
    vec3<f32>(1.0456, 0.5668, 0.0006),
    vec3<f32>(1.0026, 0.503, 0.00034),
    vec3<f32>(0.9384, 0.4412, 0.00024),
    vec3<f32>(0.8544499, 0.381, 0.00019),
    vec3<f32>(0.7514, 0.321, 0.0001),
    vec3<f32>(0.6424, 0.265, 4.999999e-05),
    vec3<f32>(0.5419, 0.217, 3e-05),
    vec3<f32>(0.4479, 0.175, 2e-05),
    vec3<f32>(0.3608, 0.1382, 1e-05),
    vec3<f32>(0.2835, 0.107, 0.0),
    vec3<f32>(0.2187, 0.0816, 0.0),
    vec3<f32>(0.1649, 0.061, 0.0),
    vec3<f32>(0.1212, 0.04458, 0.0),
    vec3<f32>(0.0874, 0.032, 0.0),
    vec3<f32>(0.0636, 0.0232, 0.0),
    vec3<f32>(0.04677, 0.017, 0.0),
    vec3<f32>(0.0329, 0.01192, 0.0),
    vec3<f32>(0.0227, 0.00821, 0.0),
    vec3<f32>(0.01584, 0.005723, 0.0),
    vec3<f32>(0.01135916, 0.004102, 0.0),
    vec3<f32>(0.008110916, 0.002929, 0.0),
    vec3<f32>(0.005790346, 0.002091, 0.0),
    vec3<f32>(0.004109457, 0.001484, 0.0),
    vec3<f32>(0.002899327, 0.001047, 0.0),
    vec3<f32>(0.00204919, 0.00074, 0.0),
    vec3<f32>(0.001439971, 0.00052, 0.0),
    vec3<f32>(0.0009999493, 0.0003611, 0.0),
    vec3<f32>(0.0006900786, 0.0002492, 0.0),
    vec3<f32>(0.0004760213, 0.0001719, 0.0),
    vec3<f32>(0.0003323011, 0.00012, 0.0),
    vec3<f32>(0.0002348261, 8.48e-05, 0.0),
    vec3<f32>(0.0001661505, 6e-05, 0.0),
    vec3<f32>(0.000117413, 4.24e-05, 0.0),
    vec3<f32>(8.307527e-05, 3e-05, 0.0),
    vec3<f32>(5.870652e-05, 2.12e-05, 0.0),
    vec3<f32>(4.150994e-05, 1.499e-05, 0.0),
    vec3<f32>(2.935326e-05, 1.06e-05, 0.0),
    vec3<f32>(2.067383e-05, 7.4657e-06, 0.0),
    vec3<f32>(1.455977e-05, 5.2578e-06, 0.0),
    vec3<f32>(1.025398e-05, 3.7029e-06, 0.0),
    vec3<f32>(7.221456e-06, 2.6078e-06, 0.0),
    vec3<f32>(5.085868e-06, 1.8366e-06, 0.0),
    vec3<f32>(3.581652e-06, 1.2934e-06, 0.0),
    vec3<f32>(2.522525e-06, 9.1093e-07, 0.0),
    vec3<f32>(1.776509e-06, 6.4153e-07, 0.0),
    vec3<f32>(1.251141e-06, 4.5181e-07, 0.0),
);

// D65 at 360 + 5 i nm, 100 at 560 nm (spectral/tables.rs).
const CIE_D65 = array<f32, 95>(
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015,
    82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736,
    104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392,
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578, 107.802, 106.296,
    104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459,
    90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939,
    83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281,
    78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765,
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054,
    46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779,
    59.4519, 55.7054, 51.959, 54.6998, 57.4406, 58.8765, 60.3125,
);

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
