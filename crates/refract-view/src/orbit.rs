//! The orbit camera: a target, a distance and two angles, dragged, panned and zoomed.

use glam::Vec3;
use refract_core::CameraDesc;

/// An orbit camera around a target.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Orbit {
    pub(crate) target: Vec3,
    pub(crate) distance: f32,
    pub(crate) yaw: f32,
    pub(crate) pitch: f32,
}

impl Orbit {
    pub(crate) fn of(desc: &CameraDesc) -> Self {
        let offset = desc.eye - desc.target;
        let distance = offset.length().max(1e-3);
        Self {
            target: desc.target,
            distance,
            yaw: offset.x.atan2(offset.z),
            pitch: (offset.y / distance).clamp(-1.0, 1.0).asin(),
        }
    }

    pub(crate) fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(sy * cp, sp, cy * cp)
    }

    /// Pixels dragged to radians.
    pub(crate) fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.01;
        self.pitch = (self.pitch + dy * 0.01).clamp(-1.5, 1.5);
    }

    pub(crate) fn pan(&mut self, dx: f32, dy: f32) {
        let forward = (self.target - self.eye()).normalize();
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(forward);
        let scale = 0.002 * self.distance;
        self.target += (-dx * right + dy * up) * scale;
    }

    pub(crate) fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(0.05, 1e4);
    }
}

#[cfg(test)]
mod tests {
    use refract_core::CameraDesc;

    use super::*;

    #[test]
    fn the_orbit_camera_starts_at_the_scene_camera() {
        let desc = CameraDesc::default();
        let orbit = Orbit::of(&desc);
        assert!((orbit.eye() - desc.eye).length() < 1e-5, "{}", orbit.eye());
        let mut moved = orbit;
        moved.orbit(100.0, 0.0);
        assert!((moved.eye() - moved.target).length() - orbit.distance < 1e-4);
        moved.zoom(1.0);
        assert!(moved.distance < orbit.distance);
    }
}
