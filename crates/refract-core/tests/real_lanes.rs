//! The two implementations of `refract_core::real` held to each other: every operation of
//! `Real`, `LaneMask` and `Vector3` on eight lanes gives, lane by lane, the bits the `f32`/`Vec3`
//! implementation gives (NaNs compared as NaN: their sign and payload may differ), on inputs that
//! include zeros of both signs, subnormals, huge numbers, infinities and NaN.

use glam::{Mat4, Vec3};
use proptest::prelude::*;
use refract_core::lanes::{F32x8, LANES, Vec3x8, mask_lanes};
use refract_core::real::{LaneMask, Real, Vector3};

/// Any `f32` a kernel may meet, the special values often.
fn number() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -4.0f32..4.0,
        1 => prop::num::f32::ANY,
        1 => prop::sample::select(vec![
            0.0, -0.0, 1.0, -1.0, 0.5, f32::MIN_POSITIVE, 1e-40, -1e-40, 1e30, -1e30,
            f32::MAX, f32::INFINITY, f32::NEG_INFINITY, f32::NAN,
        ]),
    ]
}

fn lanes() -> impl Strategy<Value = [f32; LANES]> {
    prop::array::uniform8(number())
}

fn vectors() -> impl Strategy<Value = [Vec3; LANES]> {
    prop::array::uniform8((number(), number(), number()).prop_map(|(x, y, z)| Vec3::new(x, y, z)))
}

fn same(a: f32, b: f32) -> bool {
    (a.is_nan() && b.is_nan()) || a.to_bits() == b.to_bits()
}

fn same_vec(a: Vec3, b: Vec3) -> bool {
    same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z)
}

/// Lane `i` of `lanes` against `scalar(i)` for every lane.
fn check(lanes: F32x8, scalar: impl Fn(usize) -> f32, what: &str) -> Result<(), TestCaseError> {
    for (i, lane) in lanes.to_array().into_iter().enumerate() {
        let expected = scalar(i);
        prop_assert!(
            same(lane, expected),
            "{what}, lane {i}: {lane:e} vs {expected:e}"
        );
    }
    Ok(())
}

fn check_mask(
    mask: F32x8,
    scalar: impl Fn(usize) -> bool,
    what: &str,
) -> Result<(), TestCaseError> {
    for (i, lane) in mask_lanes(mask).into_iter().enumerate() {
        prop_assert_eq!(lane, scalar(i), "{}, lane {}", what, i);
    }
    Ok(())
}

fn check_vec(
    lanes: Vec3x8,
    scalar: impl Fn(usize) -> Vec3,
    what: &str,
) -> Result<(), TestCaseError> {
    for (i, lane) in lanes.to_lanes().into_iter().enumerate() {
        let expected = scalar(i);
        prop_assert!(
            same_vec(lane, expected),
            "{what}, lane {i}: {lane} vs {expected}"
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn real_operations_agree(a in lanes(), b in lanes(), c in lanes()) {
        let (x, y, z) = (F32x8::new(a), F32x8::new(b), F32x8::new(c));
        check(x + y, |i| a[i] + b[i], "add")?;
        check(x - y, |i| a[i] - b[i], "sub")?;
        check(x * y, |i| a[i] * b[i], "mul")?;
        check(x / y, |i| a[i] / b[i], "div")?;
        check(-x, |i| -a[i], "neg")?;
        check(Real::sqrt(x), |i| Real::sqrt(a[i]), "sqrt")?;
        check(Real::abs(x), |i| Real::abs(a[i]), "abs")?;
        check(Real::floor(x), |i| Real::floor(a[i]), "floor")?;
        check(Real::trunc(x), |i| Real::trunc(a[i]), "trunc")?;
        check(Real::min(x, y), |i| Real::min(a[i], b[i]), "min")?;
        check(Real::max(x, y), |i| Real::max(a[i], b[i]), "max")?;
        check(Real::copysign(x, y), |i| Real::copysign(a[i], b[i]), "copysign")?;
        check(Real::clamp(x, F32x8::ZERO, F32x8::ONE), |i| Real::clamp(a[i], 0.0, 1.0), "clamp")?;
        check(x.map(|v| v * 3.0 + 1.0), |i| a[i] * 3.0 + 1.0, "map")?;
        check(Real::select(Real::lt(x, y), y, z), |i| Real::select(a[i] < b[i], b[i], c[i]), "select")?;
        check(refract_core::arctangent::atan2(x, y), |i| refract_core::arctangent::atan2(a[i], b[i]), "atan2")?;
        check_mask(Real::lt(x, y), |i| a[i] < b[i], "lt")?;
        check_mask(Real::le(x, y), |i| a[i] <= b[i], "le")?;
        check_mask(Real::gt(x, y), |i| a[i] > b[i], "gt")?;
        check_mask(Real::ge(x, y), |i| a[i] >= b[i], "ge")?;
        check_mask(Real::eq(x, y), |i| a[i] == b[i], "eq")?;
        check_mask(Real::is_finite(x), |i| a[i].is_finite(), "is_finite")?;
        check_mask(Real::is_nan(x), |i| a[i].is_nan(), "is_nan")?;
        check_mask(Real::is_sign_negative(x), |i| a[i].is_sign_negative(), "is_sign_negative")?;
        for (lane, expected) in Real::to_lane_array(x).into_iter().zip(a) {
            prop_assert!(same(lane, expected));
        }
    }

    #[test]
    fn masks_agree(a in lanes(), b in lanes()) {
        let (x, y) = (F32x8::new(a), F32x8::new(b));
        let (m, n) = (Real::lt(x, y), Real::is_finite(x));
        check_mask(m & n, |i| a[i] < b[i] && a[i].is_finite(), "and")?;
        check_mask(m | n, |i| a[i] < b[i] || a[i].is_finite(), "or")?;
        check_mask(!m, |i| a[i].partial_cmp(&b[i]) != Some(std::cmp::Ordering::Less), "not")?;
        let lanes: Vec<bool> = m.lanes().collect();
        prop_assert_eq!(m.all(), lanes.iter().all(|l| *l));
        prop_assert_eq!(m.any(), lanes.iter().any(|l| *l));
        let mut set = m;
        set.set(3, true);
        set.set(5, false);
        check_mask(set, |i| match i { 3 => true, 5 => false, _ => lanes[i] }, "set")?;
        prop_assert!(<F32x8 as LaneMask>::splat(true).all() && !<F32x8 as LaneMask>::splat(false).any());
    }

    #[test]
    fn vector_operations_agree(a in vectors(), b in vectors(), s in lanes(), m in prop::array::uniform16(number())) {
        let (u, v, t) = (Vec3x8::from_lanes(&a), Vec3x8::from_lanes(&b), F32x8::new(s));
        let matrix = Mat4::from_cols_array(&m);
        check_vec(u + v, |i| a[i] + b[i], "add")?;
        check_vec(u - v, |i| a[i] - b[i], "sub")?;
        check_vec(u * v, |i| a[i] * b[i], "mul")?;
        check_vec(u * t, |i| a[i] * s[i], "scale")?;
        check_vec(-u, |i| -a[i], "neg")?;
        check(u.dot(v), |i| a[i].dot(b[i]), "dot")?;
        check(Vector3::length(u), |i| a[i].length(), "length")?;
        check_vec(u.cross(v), |i| a[i].cross(b[i]), "cross")?;
        check_vec(u.normalize_or_zero(), |i| a[i].normalize_or_zero(), "normalize_or_zero")?;
        check_vec(Vector3::lerp(u, v, t), |i| a[i].lerp(b[i], s[i]), "lerp")?;
        check_vec(Vec3x8::transform_vector3(&matrix, u), |i| matrix.transform_vector3(a[i]), "transform_vector3")?;
        check_mask(u.is_zero(), |i| a[i] == Vec3::ZERO, "is_zero")?;
        check_mask(Vector3::is_finite(u), |i| a[i].is_finite(), "is_finite")?;
        let (n, ok) = u.try_normalize();
        check_mask(ok, |i| a[i].try_normalize().is_some(), "try_normalize ok")?;
        for (i, lane) in mask_lanes(ok).into_iter().enumerate() {
            if lane {
                prop_assert!(same_vec(n.lane(i), a[i].try_normalize().unwrap_or(Vec3::NAN)));
            }
        }
        check_vec(Vector3::select(Real::lt(t, F32x8::ZERO), u, v), |i| if s[i] < 0.0 { a[i] } else { b[i] }, "select")?;
        check_vec(Vec3x8::gather(|i| b[i]), |i| b[i], "gather")?;
        let mut w = u;
        w.set_lane(6, b[6]);
        check_vec(w, |i| if i == 6 { b[6] } else { a[i] }, "set_lane")?;
        check_vec(Vec3x8::new(u.x, v.y, t), |i| Vec3::new(a[i].x, b[i].y, s[i]), "new")?;
    }
}
