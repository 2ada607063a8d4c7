//! The viewer's exact reference, refined progressively on the CPU in a background thread
//! while the camera rests: 1/8, 1/4, 1/2, then full resolution (the last with its AOVs, for
//! the error maps); a newer request (the camera moved) abandons older work between levels.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};

use refract_core::CameraDesc;
use refract_scene::{Frame, FrameOutputs, MethodId, MethodParams, Renderer, Scene};
use refract_trace::ReferenceRenderer;

/// One level of a reference: the frame at `scale` of the requested size.
pub struct Level {
    /// The request it answers.
    pub generation: u64,
    /// The frame (colour; AOVs too at full resolution).
    pub frame: Frame,
    /// Whether this is the full-resolution level.
    pub full: bool,
}

struct Request {
    generation: u64,
    scene: Arc<Scene>,
    camera: CameraDesc,
}

/// The background worker.
pub struct ProgressiveReference {
    requests: Sender<Request>,
    levels: Receiver<Level>,
    latest: Arc<AtomicU64>,
    requested: Option<(CameraDesc, u64)>,
}

impl ProgressiveReference {
    /// Starts the worker thread.
    pub fn start() -> Self {
        let (requests, inbox) = channel::<Request>();
        let (outbox, levels) = channel::<Level>();
        let latest = Arc::new(AtomicU64::new(0));
        let current = Arc::clone(&latest);
        std::thread::spawn(move || {
            let mut tracer = ReferenceRenderer::new();
            let settings = MethodParams::defaults(MethodId::Reference);
            while let Ok(mut request) = inbox.recv() {
                // Only the newest request matters.
                while let Ok(newer) = inbox.try_recv() {
                    request = newer;
                }
                if tracer.prepare(&request.scene).is_err() {
                    continue;
                }
                for divisor in [8u32, 4, 2, 1] {
                    if current.load(Ordering::Relaxed) != request.generation {
                        break;
                    }
                    let desc = CameraDesc {
                        width: (request.camera.width / divisor).max(1),
                        height: (request.camera.height / divisor).max(1),
                        ..request.camera
                    };
                    let Ok(camera) = refract_core::Camera::new(desc) else {
                        break;
                    };
                    let outputs = if divisor == 1 {
                        FrameOutputs::ColorAndAovs
                    } else {
                        FrameOutputs::Color
                    };
                    let mut frame = Frame::default();
                    if tracer
                        .render(&camera, &settings, outputs, &mut frame)
                        .is_err()
                    {
                        break;
                    }
                    let level = Level {
                        generation: request.generation,
                        frame,
                        full: divisor == 1,
                    };
                    if outbox.send(level).is_err() {
                        return;
                    }
                }
            }
        });
        Self {
            requests,
            levels,
            latest,
            requested: None,
        }
    }

    /// Asks for the reference of `camera` (no-op when it is the one last asked for); returns
    /// the request's generation.
    pub fn request(&mut self, scene: &Arc<Scene>, camera: CameraDesc, force: bool) -> u64 {
        if let Some((previous, generation)) = self.requested
            && previous == camera
            && !force
        {
            return generation;
        }
        let generation = self.latest.fetch_add(1, Ordering::Relaxed) + 1;
        self.requested = Some((camera, generation));
        let _ = self.requests.send(Request {
            generation,
            scene: Arc::clone(scene),
            camera,
        });
        generation
    }

    /// The newest finished level of `generation`, if any arrived.
    pub fn poll(&self, generation: u64) -> Option<Level> {
        let mut newest = None;
        while let Ok(level) = self.levels.try_recv() {
            if level.generation == generation {
                newest = Some(level);
            }
        }
        newest
    }
}
