//! # refract-engines
//!
//! The engines' own renderers, so that their glass is measured as they ship it and not only as
//! refract re-implements it (`docs/engines.md`). A scene is exported as glTF 2.0
//! ([`refract_eval::gltf_export`]); `engines/render.mjs` (Node, puppeteer-core) opens the
//! engine's page (`engines/<engine>/index.html`) in headless Chromium, which loads the glTF with
//! the engine's own loader, renders it into a float render target with every setting that
//! changes pixels pinned (pixel ratio 1, no tone mapping, no MSAA, linear output, clear alpha 1,
//! transmission at full resolution) and hands the linear pixels back. The engines are the npm
//! packages of `engines/package.json`, pinned by its lockfile (`npm ci --prefix engines`).
//!
//! What is needed and missing (Node, Chromium, `engines/node_modules`) is one
//! [`EngineError::Unavailable`] line, which callers report as a skip, as a missing GPU is.

use std::io::{BufRead, BufReader, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use glam::Vec3;
use refract_eval::gltf_export::position_from_code;
use refract_scene::Frame;

/// An engine refract drives in the browser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Engine {
    /// three.js (`three` on npm): `MeshPhysicalMaterial` transmission from glTF's
    /// `KHR_materials_transmission`, `_ior` and `_volume`.
    Threejs,
    /// Babylon.js (`babylonjs` and `babylonjs-loaders` on npm): `PBRMaterial` sub-surface
    /// refraction from the same extensions, through the glTF loader's transmission helper.
    Babylon,
    /// The Khronos glTF Sample Viewer's renderer (`@khronosgroup/gltf-viewer` on npm), the
    /// extensions' reference implementation and the renderer of Khronos' render-fidelity
    /// comparisons: the same extensions in its own PBR shader.
    GltfViewer,
}

impl Engine {
    /// Every engine.
    pub const ALL: [Engine; 3] = [Engine::Threejs, Engine::Babylon, Engine::GltfViewer];

    /// The engines of the default job (`cargo run --release`): all but the glTF Sample Viewer,
    /// whose image-based-light prefilter (a 256² cube map, 1,024 GGX samples a texel) takes
    /// about 80 s on SwiftShader, more than the job's budget of about 6 minutes has left;
    /// `refract compare --engines gltf-viewer` and `refract claims` run it.
    pub const DEFAULT_JOB: [Engine; 2] = [Engine::Threejs, Engine::Babylon];

    /// The id on the command line and in `engines/<id>/`.
    pub const fn id(self) -> &'static str {
        match self {
            Engine::Threejs => "threejs",
            Engine::Babylon => "babylon",
            Engine::GltfViewer => "gltf-viewer",
        }
    }

    /// Whether the position codes its glass shows decode to the point it looks up
    /// ([`Variant::Position`]). Not for the glTF Sample Viewer: its transmission is weighted
    /// by `1 − (f0 A + B)` from its GGX look-up table (its `getIBLVolumeRefraction`) whatever
    /// `KHR_materials_specular` says, so the codes through its glass are scaled, by 0.96 at
    /// normal incidence and less towards the rim, and decode centimetres off the lookup
    /// point (`docs/engines.md`); its `P_geom` is not measured.
    pub const fn positions_through_glass(self) -> bool {
        !matches!(self, Engine::GltfViewer)
    }

    /// Whether a request may leave `departure` out of this engine's glass
    /// ([`EngineRequest::without`]): three.js's and Babylon.js's, whose glass shaders their
    /// pages edit (`docs/engines.md`); not the glTF Sample Viewer's.
    pub const fn leaves_out(self, departure: Departure) -> bool {
        match self {
            Engine::Threejs | Engine::Babylon => match departure {
                Departure::Reflection | Departure::FresnelWeight | Departure::FilteredRead => true,
            },
            Engine::GltfViewer => false,
        }
    }

    /// The npm package whose version names the engine.
    pub const fn npm_package(self) -> &'static str {
        match self {
            Engine::Threejs => "three",
            Engine::Babylon => "babylonjs",
            Engine::GltfViewer => "@khronosgroup/gltf-viewer",
        }
    }
}

/// Which file of the export a frame renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// `scene.gltf` under `environment.hdr`: the picture.
    Color,
    /// `position-coded.gltf`, no environment: each pixel's colour is the position code of the
    /// world point it shows, black where it shows none ([`decode_positions`]).
    Position,
}

impl Variant {
    const fn id(self) -> &'static str {
        match self {
            Variant::Color => "color",
            Variant::Position => "position",
        }
    }
}

/// A behaviour of an engine's glass that its re-implementation (`volume-thickness`) does not
/// model, which a request can leave out of the engine's frame to measure that behaviour's
/// share of the difference (`docs/engines.md`, "The engines against `volume-thickness`").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Departure {
    /// The environment's specular reflection off the glass (three.js: `radiance +=
    /// iblRadiance` of `lights_fragment_maps`; Babylon.js: `finalRadianceScaled` of
    /// `pbrBlockFinalLitComponents`).
    Reflection,
    /// The Fresnel weight of the environment BRDF on the transmitted light (three.js: the
    /// `(1 − F)` of `getIBLVolumeRefraction`; Babylon.js: `1 −
    /// specularEnvironmentReflectance` in `pbrBlockSubSurface`).
    FresnelWeight,
    /// The filtered read of the transmission target at a roughness LOD (three.js: bicubic, at
    /// the level of `max(roughness, 0.045)` plus the normal's screen-space change; Babylon.js:
    /// bilinear at the level of `alphaG`): the nearest texel of level 0 instead, clamped to
    /// the target, as `volume-thickness` reads.
    FilteredRead,
}

impl Departure {
    /// Every departure.
    pub const ALL: [Departure; 3] = [
        Departure::Reflection,
        Departure::FresnelWeight,
        Departure::FilteredRead,
    ];

    /// The id in a request (`engines/render.mjs`'s `DEPARTURES`).
    pub const fn id(self) -> &'static str {
        match self {
            Departure::Reflection => "reflection",
            Departure::FresnelWeight => "fresnel-weight",
            Departure::FilteredRead => "filtered-read",
        }
    }
}

/// The frames to render of one export, in one browser session.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EngineRequest {
    /// Which files, one frame each.
    pub variants: Vec<Variant>,
    /// Width in pixels, `1..=4096`.
    pub width: u32,
    /// Height in pixels, `1..=4096`.
    pub height: u32,
    /// Leave the refractor out (camera and background checks).
    pub hide_refractor: bool,
    /// Behaviours left out of the engine's glass (each one [`Engine::leaves_out`]); empty for
    /// the engine as it ships.
    pub without: Vec<Departure>,
}

impl EngineRequest {
    /// `variants` at `width × height`, of the engine as it ships: the refractor shown, nothing
    /// left out ([`EngineRequest::without`]).
    pub fn new(variants: Vec<Variant>, width: u32, height: u32) -> Self {
        Self {
            variants,
            width,
            height,
            hide_refractor: false,
            without: Vec::new(),
        }
    }

    /// A [`EngineRequest::Request`](EngineError::Request) error naming the field where a side
    /// is outside `1..=MAX_SIDE` or `engine` cannot leave a departure out.
    fn check(&self, engine: Engine) -> Result<(), EngineError> {
        for (side, value) in [("width", self.width), ("height", self.height)] {
            if !(1..=MAX_SIDE).contains(&value) {
                return Err(EngineError::Request(format!(
                    "{side} {value}: expected 1..={MAX_SIDE} pixels for an engine frame"
                )));
            }
        }
        match self.without.iter().find(|d| !engine.leaves_out(**d)) {
            Some(departure) => Err(EngineError::Request(format!(
                "without {}: {} cannot leave it out of its glass",
                departure.id(),
                engine.id()
            ))),
            None => Ok(()),
        }
    }
}

/// The largest side [`EngineRequest`] takes (what `engines/render.mjs` accepts).
pub const MAX_SIDE: u32 = 4096;

/// A frame an engine rendered.
#[derive(Clone, Debug)]
pub struct EngineFrame {
    /// The engine and its version, `threejs@0.187.0`.
    pub label: String,
    /// Linear RGB (alpha dropped), rows from the top.
    pub frame: Frame,
    /// The engine's second frame (the first compiles its programs), milliseconds between two
    /// `gl.finish()` in the page (SwiftShader: a CPU rasteriser, not a GPU time).
    pub ms: f64,
    /// What the page reported: engine, version, every pinned setting.
    pub metadata: serde_json::Value,
}

/// Why an engine frame could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// What the engines need is not installed (one line naming what and how to get it).
    #[error("{0}")]
    Unavailable(String),
    /// A request out of range.
    #[error("{0}")]
    Request(String),
    /// The driver or the page failed.
    #[error("{engine}: {message}")]
    Driver {
        /// The engine.
        engine: &'static str,
        /// What `engines/render.mjs` said.
        message: String,
    },
    /// A file of the frame could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// Where the engines are found: Node, Chromium and `engines/` with its `node_modules`.
#[derive(Clone, Debug)]
pub struct EngineDriver {
    node: PathBuf,
    browser: PathBuf,
    engines_dir: PathBuf,
}

/// The first `name` on `PATH`.
fn find_on_path(name: &str) -> Option<PathBuf> {
    std::env::split_paths(&std::env::var_os("PATH")?)
        .map(|dir| dir.join(name))
        .find(|path| path.is_file())
}

impl EngineDriver {
    /// Finds Node (`REFRACT_NODE`, else `node` on `PATH`), Chromium (`REFRACT_CHROMIUM`, else
    /// `chromium` or `chromium-browser` on `PATH`) and `engines/` (`REFRACT_ENGINES_DIR`, else
    /// the workspace's) with its npm packages installed.
    pub fn locate() -> Result<Self, EngineError> {
        let program = |variable: &str, names: &[&str], what: &str| {
            std::env::var_os(variable)
                .map(PathBuf::from)
                .or_else(|| names.iter().find_map(|n| find_on_path(n)))
                .ok_or_else(|| {
                    EngineError::Unavailable(format!(
                        "no {what} ({} on PATH, or {variable}) for the engines' own renders",
                        names.join(" or ")
                    ))
                })
        };
        let node = program("REFRACT_NODE", &["node"], "Node.js")?;
        let browser = program(
            "REFRACT_CHROMIUM",
            &["chromium", "chromium-browser"],
            "Chromium",
        )?;
        let engines_dir = std::env::var_os("REFRACT_ENGINES_DIR")
            .map(PathBuf::from)
            .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../engines"));
        if !engines_dir.join("node_modules/puppeteer-core").is_dir() {
            return Err(EngineError::Unavailable(format!(
                "{}: the engines' npm packages are not installed (run `npm ci --prefix {}`)",
                engines_dir.join("node_modules").display(),
                engines_dir.display()
            )));
        }
        Ok(Self {
            node,
            browser,
            engines_dir,
        })
    }

    /// The installed version of `engine`'s npm package.
    pub fn version(&self, engine: Engine) -> Result<String, EngineError> {
        let path = self
            .engines_dir
            .join("node_modules")
            .join(engine.npm_package())
            .join("package.json");
        let text = std::fs::read_to_string(&path).map_err(|source| EngineError::Io {
            path: path.clone(),
            source,
        })?;
        serde_json::from_str::<serde_json::Value>(&text)
            .ok()
            .and_then(|json| json["version"].as_str().map(str::to_owned))
            .ok_or_else(|| EngineError::Driver {
                engine: engine.id(),
                message: format!("{}: no version field", path.display()),
            })
    }

    /// Renders the frames of `request` of the export in `export_dir` (what
    /// [`refract_eval::gltf_export`] wrote) with `engine`, one per variant, in order, in a
    /// browser started for this one request. Several scenes: [`EngineDriver::session`].
    pub fn render(
        &self,
        engine: Engine,
        export_dir: &Path,
        request: &EngineRequest,
    ) -> Result<Vec<EngineFrame>, EngineError> {
        request.check(engine)?;
        self.session(engine)?.render(export_dir, request)
    }

    /// Starts `engine`'s page in headless Chromium (`engines/render.mjs --serve`) for as many
    /// requests as [`EngineSession::render`] is given; the browser closes when the session is
    /// dropped.
    pub fn session(&self, engine: Engine) -> Result<EngineSession, EngineError> {
        let driver_error = |message: String| EngineError::Driver {
            engine: engine.id(),
            message,
        };
        let io_error = |source| EngineError::Io {
            path: std::env::temp_dir(),
            source,
        };
        // What Node and the page print goes to a file, read back when a request fails (a pipe
        // nobody reads would stall the browser once full).
        let log = tempfile::tempfile().map_err(io_error)?;
        let mut child = Command::new(&self.node)
            .arg(self.engines_dir.join("render.mjs"))
            .args(["--engine", engine.id(), "--serve", "--browser"])
            .arg(&self.browser)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(log.try_clone().map_err(io_error)?)
            .spawn()
            .map_err(|err| driver_error(format!("cannot run {}: {err}", self.node.display())))?;
        let (Some(stdin), Some(stdout)) = (child.stdin.take(), child.stdout.take()) else {
            let _ = child.kill();
            return Err(driver_error("no pipes to engines/render.mjs".into()));
        };
        Ok(EngineSession {
            engine,
            child,
            stdin: Some(stdin),
            replies: BufReader::new(stdout),
            log,
        })
    }
}

/// One engine's page in one headless Chromium, kept open across requests
/// (`engines/render.mjs --serve`): the engine prefilters an environment once for every scene
/// that shares it (three.js's PMREM, Babylon's cube: 10-50 s each on SwiftShader) and
/// compiles its programs once. A scene rendered after others gives the same bits as rendered
/// alone (`tests/engines.rs`).
#[derive(Debug)]
pub struct EngineSession {
    engine: Engine,
    child: Child,
    /// `None` once closed, which ends the serving loop.
    stdin: Option<ChildStdin>,
    replies: BufReader<ChildStdout>,
    log: std::fs::File,
}

impl EngineSession {
    /// The engine this session renders with.
    pub fn engine(&self) -> Engine {
        self.engine
    }

    /// Renders the frames of `request` of the export in `export_dir` (what
    /// [`refract_eval::gltf_export`] wrote), one per variant, in order.
    pub fn render(
        &mut self,
        export_dir: &Path,
        request: &EngineRequest,
    ) -> Result<Vec<EngineFrame>, EngineError> {
        let engine = self.engine;
        request.check(engine)?;
        let driver_error = |message: String| EngineError::Driver {
            engine: engine.id(),
            message,
        };
        let scratch = tempfile::tempdir().map_err(|source| EngineError::Io {
            path: std::env::temp_dir(),
            source,
        })?;
        let utf8 = |path: &Path| {
            path.to_str().map(str::to_owned).ok_or_else(|| {
                EngineError::Request(format!(
                    "{}: the engine driver takes UTF-8 paths only",
                    path.display()
                ))
            })
        };
        let line = serde_json::json!({
            "scene": utf8(export_dir)?,
            "variants": request.variants.iter().map(|v| v.id()).collect::<Vec<_>>(),
            "width": request.width,
            "height": request.height,
            "out": utf8(scratch.path())?,
            "hideRefractor": request.hide_refractor,
            "without": request.without.iter().map(|d| d.id()).collect::<Vec<_>>(),
        });
        let answer = self.exchange(&line.to_string()).map_err(|why| {
            driver_error(format!("engines/render.mjs {why}: {}", self.log_text()))
        })?;
        let answer: serde_json::Value = serde_json::from_str(&answer).map_err(|err| {
            driver_error(format!("unreadable reply from engines/render.mjs: {err}"))
        })?;
        if let Some(error) = answer["error"].as_str() {
            return Err(driver_error(error.to_owned()));
        }
        let replies = answer["frames"].as_array().cloned().unwrap_or_default();
        if replies.len() != request.variants.len() {
            return Err(driver_error(format!(
                "{} frames for {} variants",
                replies.len(),
                request.variants.len()
            )));
        }
        request
            .variants
            .iter()
            .zip(replies)
            .map(|(variant, metadata)| {
                let path = scratch.path().join(format!("{}.f32", variant.id()));
                let bytes = std::fs::read(&path).map_err(|source| EngineError::Io {
                    path: path.clone(),
                    source,
                })?;
                let frame = frame_of(&bytes, request.width, request.height).ok_or_else(|| {
                    driver_error(format!(
                        "{}: {} bytes of pixels",
                        path.display(),
                        bytes.len()
                    ))
                })?;
                let version = metadata["version"].as_str().unwrap_or("?");
                Ok(EngineFrame {
                    label: format!("{}@{version}", engine.id()),
                    frame,
                    ms: metadata["ms"].as_f64().unwrap_or(f64::NAN),
                    metadata,
                })
            })
            .collect()
    }

    /// Sends one request line and reads the answer line; the error says what went wrong
    /// ("exited (status)", "is closed", ...) for a message that goes on with the log.
    fn exchange(&mut self, line: &str) -> Result<String, String> {
        let stdin = self.stdin.as_mut().ok_or("is closed")?;
        let sent = writeln!(stdin, "{line}").and_then(|()| stdin.flush());
        let mut answer = String::new();
        let read = sent.and_then(|()| self.replies.read_line(&mut answer));
        match read {
            Ok(n) if n > 0 => Ok(answer),
            _ => {
                self.stdin = None;
                let status = self
                    .child
                    .wait()
                    .map_or_else(|e| e.to_string(), |s| s.to_string());
                Err(format!("exited ({status})"))
            }
        }
    }

    /// What Node and the page printed, trimmed.
    fn log_text(&mut self) -> String {
        let mut text = String::new();
        let _ = self.log.seek(SeekFrom::Start(0));
        let _ = self.log.read_to_string(&mut text);
        text.trim().to_owned()
    }
}

impl Drop for EngineSession {
    /// Closes the input, which makes `render.mjs` close the browser and exit; kills it if it
    /// has not within 10 s.
    fn drop(&mut self) {
        self.stdin = None;
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        while std::time::Instant::now() < deadline {
            match self.child.try_wait() {
                Ok(Some(_)) | Err(_) => return,
                Ok(None) => std::thread::sleep(std::time::Duration::from_millis(20)),
            }
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A frame of little-endian `f32` RGBA pixels, rows from the top (alpha dropped); `None` when
/// `bytes` is not `width × height` pixels.
fn frame_of(bytes: &[u8], width: u32, height: u32) -> Option<Frame> {
    let pixels = (width as usize) * (height as usize);
    if bytes.len() != pixels * 16 {
        return None;
    }
    let mut frame = Frame::new(width, height);
    for (color, rgba) in frame.color.iter_mut().zip(bytes.chunks_exact(16)) {
        let channel = |k: usize| {
            f32::from_le_bytes([
                rgba[4 * k],
                rgba[4 * k + 1],
                rgba[4 * k + 2],
                rgba[4 * k + 3],
            ])
        };
        *color = Vec3::new(channel(0), channel(1), channel(2));
    }
    Some(frame)
}

/// The world point each pixel of a [`Variant::Position`] frame shows (`None` where black: the
/// pixel shows no object), decoded with the export's position-code bounds.
pub fn decode_positions(frame: &Frame, bounds: (Vec3, Vec3)) -> Vec<Option<Vec3>> {
    frame
        .color
        .iter()
        .map(|&code| (code.max_element() > 0.0).then(|| position_from_code(code, bounds)))
        .collect()
}
