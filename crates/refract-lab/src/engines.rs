//! The engines' own renderers in a comparison (`refract_engines`, `docs/engines.md`): each
//! scene exported as glTF once, then each engine renders its colour and its position-coded
//! frame in one browser session; the frame the metrics read is the colour with two layers:
//! `Covered` (the reference's refractor pixels: the engines rasterise the same triangles with
//! the same pixel-centre rule) and `P_geom` (the world point the position-coded frame shows
//! there, NaN where it shows none).

use glam::Vec3;
use std::sync::Mutex;

use refract_engines::{
    Engine, EngineDriver, EngineError, EngineRequest, EngineSession, Variant, decode_positions,
};
use refract_eval::gltf_export::{export_gltf, position_code_bounds};
use refract_eval::metrics::MetricsRecord;
use refract_scene::{Aov, Frame, Layer, Scene};

use crate::backends::GpuPolicy;
use crate::progress::{Note, Progress};

/// The backend column of an engine's rows: where it ran (Chromium's WebGL2 on SwiftShader).
pub const ENGINE_BACKEND: &str = "webgl";

/// Parses an `--engines` list (`threejs`, `babylon`, `gltf-viewer`; `none` for no engine).
pub fn parse_engines(names: &[String]) -> crate::Result<Vec<Engine>> {
    let mut engines = Vec::new();
    for name in names {
        if name == "none" {
            continue;
        }
        match Engine::ALL.iter().find(|e| e.id() == name) {
            Some(&engine) => engines.push(engine),
            None => crate::bail!(
                "--engines: unknown engine `{name}`; expected {} or none",
                Engine::ALL.map(Engine::id).join(", ")
            ),
        }
    }
    Ok(engines)
}

/// The engines a command runs and the driver that runs them: one browser session per engine,
/// started at its first scene and kept for the others (so an environment the scenes share is
/// prefiltered once), closed when this is dropped.
pub struct EngineRenderers {
    driver: EngineDriver,
    engines: Vec<Engine>,
    sessions: Mutex<Vec<EngineSession>>,
}

/// One engine's frame of a scene, ready for the metrics.
pub struct EngineFrame {
    /// The engine.
    pub engine: Engine,
    /// `threejs@0.187.0`.
    pub label: String,
    /// Colour, `Covered` and `P_geom`.
    pub frame: Frame,
}

impl EngineRenderers {
    /// The driver of `engines` (`None` for no engine); what is missing is an error with
    /// [`GpuPolicy::Required`], a skip note with [`GpuPolicy::IfAvailable`].
    pub fn open(
        engines: &[Engine],
        policy: GpuPolicy,
        progress: &dyn Progress,
    ) -> crate::Result<Option<Self>> {
        if engines.is_empty() {
            return Ok(None);
        }
        match EngineDriver::locate() {
            Ok(driver) => Ok(Some(Self {
                driver,
                engines: engines.to_vec(),
                sessions: Mutex::new(Vec::new()),
            })),
            Err(EngineError::Unavailable(why)) if policy == GpuPolicy::IfAvailable => {
                progress.note(Note::Skipped(format!(
                    "{why}: the engines' own renders are skipped"
                )));
                Ok(None)
            }
            Err(err) => crate::bail!("{err}"),
        }
    }

    /// How many engines run.
    pub fn len(&self) -> usize {
        self.engines.len()
    }

    /// Whether no engine runs.
    pub fn is_empty(&self) -> bool {
        self.engines.is_empty()
    }

    /// Every engine's frame of `scene` at `width × height`, `truth` being the reference's
    /// frame (its `Covered` layer).
    pub fn render(
        &self,
        scene: &Scene,
        truth: &Frame,
        width: u32,
        height: u32,
    ) -> crate::Result<Vec<EngineFrame>> {
        self.render_engines(&self.engines, scene, truth, width, height)
    }

    /// [`Self::render`] with `engines` only (each must be one this driver was opened for).
    pub fn render_engines(
        &self,
        engines: &[Engine],
        scene: &Scene,
        truth: &Frame,
        width: u32,
        height: u32,
    ) -> crate::Result<Vec<EngineFrame>> {
        if let Some(other) = engines.iter().find(|e| !self.engines.contains(e)) {
            crate::bail!("the engine driver was not opened for {}", other.id());
        }
        let export = tempfile::tempdir().map_err(crate::LabError::Os)?;
        export_gltf(scene)?.write(export.path())?;
        let bounds = position_code_bounds(scene);
        let request = |engine: Engine| {
            let variants = if engine.positions_through_glass() {
                vec![Variant::Color, Variant::Position]
            } else {
                vec![Variant::Color]
            };
            EngineRequest::new(variants, width, height)
        };
        let covered = truth
            .flag(Aov::Covered)
            .map(<[bool]>::to_vec)
            .unwrap_or_else(|| vec![false; truth.pixel_count()]);
        let mut frames = Vec::new();
        let mut sessions = self
            .sessions
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        for &engine in engines {
            let index = match sessions.iter().position(|s| s.engine() == engine) {
                Some(index) => index,
                None => {
                    let session = self
                        .driver
                        .session(engine)
                        .map_err(|err| crate::LabError::invalid(err.to_string()))?;
                    sessions.push(session);
                    sessions.len() - 1
                }
            };
            let rendered = sessions[index].render(export.path(), &request(engine));
            if rendered.is_err() {
                // A failed request may have left the page in any state: the next scene starts
                // a fresh browser.
                sessions.swap_remove(index);
            }
            let mut rendered = rendered.map_err(|err| crate::LabError::invalid(err.to_string()))?;
            let position = engine
                .positions_through_glass()
                .then(|| rendered.pop().expect("two variants requested"));
            let color = rendered.pop().expect("the colour variant requested");
            let mut frame = color.frame;
            frame.insert_layer(Aov::Covered, Layer::Flag(covered.clone()));
            // Without decodable positions (`Engine::positions_through_glass`) the frame has no
            // `P_geom` layer, and its `P_geom` metrics are "–", not misses.
            if let Some(position) = position {
                let p_geom: Vec<Vec3> = decode_positions(&position.frame, bounds)
                    .into_iter()
                    .zip(&covered)
                    .map(|(p, &glass)| p.filter(|_| glass).unwrap_or(Vec3::NAN))
                    .collect();
                frame.insert_layer(Aov::PGeom, Layer::Vec3(p_geom));
            }
            frames.push(EngineFrame {
                engine,
                label: color.label,
                frame,
            });
        }
        Ok(frames)
    }
}

/// The metrics of an engine's frame (colour, `Covered`, `P_geom`, as [`EngineRenderers::render`]
/// makes it) against the reference `truth`: the methods' colour metrics and the nearby-geometry
/// metrics from its `P_geom` where it has one (not for an engine whose glass does not pass
/// position codes, `Engine::positions_through_glass`: those metrics stay absent, not misses);
/// with the error maps.
pub fn engine_record(
    truth: &Frame,
    frame: &Frame,
    scene: &Scene,
    camera: &refract_core::Camera,
) -> (MetricsRecord, refract_eval::metrics::ErrorMaps) {
    let (mut record, maps) =
        refract_eval::metrics::evaluate(truth, frame, camera, scene.refractor.diameter());
    if frame.vec3(Aov::PGeom).is_some() {
        refract_eval::metrics::evaluate_nearby(truth, frame, scene, camera, None, &mut record);
    }
    (record, maps)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An engine frame without `P_geom` (the glTF Sample Viewer's) has no nearby-geometry
    /// metrics: not 100 % misses, as it had when its missing layer read as "no hit".
    #[test]
    fn a_frame_without_positions_has_no_miss_rate() {
        let scene = refract_eval::load_scene("chart").expect("chart").scene;
        let camera = scene.camera(4, 4).expect("camera");
        let mut truth = Frame::new(4, 4);
        truth.insert_layer(Aov::Covered, Layer::Flag(vec![true; 16]));
        truth.insert_layer(Aov::PGeom, Layer::Vec3(vec![Vec3::ZERO; 16]));
        let mut frame = Frame::new(4, 4);
        frame.insert_layer(Aov::Covered, Layer::Flag(vec![true; 16]));
        let (record, _) = engine_record(&truth, &frame, &scene, &camera);
        assert_eq!(record.nearby_miss_rate, None);
        assert!(record.flip_mean.is_some());
        frame.insert_layer(Aov::PGeom, Layer::Vec3(vec![Vec3::NAN; 16]));
        let (record, _) = engine_record(&truth, &frame, &scene, &camera);
        assert_eq!(record.nearby_miss_rate, Some(1.0));
    }

    #[test]
    fn engines_are_parsed_by_id_and_a_wrong_one_names_the_choices() {
        let names = |list: &[&str]| list.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>();
        assert_eq!(
            parse_engines(&names(&["threejs"])).expect("threejs"),
            [Engine::Threejs]
        );
        assert!(parse_engines(&names(&["none"])).expect("none").is_empty());
        let err = parse_engines(&names(&["unity"])).expect_err("unknown");
        assert!(
            err.to_string()
                .contains("`unity`; expected threejs, babylon, gltf-viewer or none"),
            "{err}"
        );
    }
}
