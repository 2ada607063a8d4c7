// The Khronos glTF Sample Viewer (`@khronosgroup/gltf-viewer`, the renderer of Khronos' glTF
// Sample Viewer and of its render-fidelity comparisons) renders a scene of `refract export
// --format gltf`, and the pixels go back to refract as linear floats (engines/README.md). Every
// setting that changes pixels is pinned here and returned in `settings`.
//
// The renderer draws its last pass into the default framebuffer with its output curve applied
// (`toneMap`: exposure, then `pow(c, 1/2.2)`). Here that pass lands in a float framebuffer
// instead (`bindFramebuffer(..., null)` is redirected to it), the tone map is NONE and the
// exposure 1, so each read-back value is `c^(1/2.2)` in f32 and `pow(v, 2.2)` gives the linear
// colour back (to about 1e-7 relative) without the 8-bit quantisation of a canvas.
import { GltfState, GltfView, ResourceLoader } from '/engines/node_modules/@khronosgroup/gltf-viewer/dist/gltf-viewer.module.js';
import { topDownBase64 } from '../common.js';

const VERSION = '1.1.0';
// The viewer's output curve (its tonemapping.glsl: GAMMA = 2.2).
const GAMMA = 2.2;
// refract's lat-long orientation against the viewer's (its `environmentRotation`, degrees; the
// viewer's default is 90): held by the background test, crates/refract-engines/tests/engines.rs.
const ENVIRONMENT_ROTATION_DEG = 90;
// The sheen look-up table the viewer loads with every environment is not in the npm package;
// no material refract exports has sheen, so any image does: one black pixel.
const SHEEN_LUT = 'data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNkYPhfDwAChwGA60e6kgAAAABJRU5ErkJggg==';

let canvas = null;
let gl = null;
let view = null;
let target = null;
// The environments by the content of their file (render.mjs's `sceneEnvironment.key`).
const environments = new Map();

/// A float RGBA framebuffer with depth, `width × height`, that stands in for the canvas.
function floatTarget(width, height) {
  if (target && target.width === width && target.height === height) return target;
  if (target) {
    gl.deleteFramebuffer(target.framebuffer);
    gl.deleteTexture(target.color);
    gl.deleteRenderbuffer(target.depth);
  }
  const color = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, color);
  gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, width, height);
  const depth = gl.createRenderbuffer();
  gl.bindRenderbuffer(gl.RENDERBUFFER, depth);
  gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, width, height);
  const framebuffer = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, color, 0);
  gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depth);
  const status = gl.checkFramebufferStatus(gl.FRAMEBUFFER);
  if (status !== gl.FRAMEBUFFER_COMPLETE) throw new Error(`float framebuffer incomplete: 0x${status.toString(16)}`);
  target = { framebuffer, color, depth, width, height };
  return target;
}

function setUp() {
  canvas = document.createElement('canvas');
  gl = canvas.getContext('webgl2', { antialias: false, alpha: false, depth: true, premultipliedAlpha: false });
  if (!gl) throw new Error('no WebGL2 context');
  if (!gl.getExtension('EXT_color_buffer_float')) throw new Error('no EXT_color_buffer_float: cannot read floats back');
  // The canvas is never drawn to: its binding is the float target's.
  const bind = gl.bindFramebuffer.bind(gl);
  gl.bindFramebuffer = (kind, framebuffer) => bind(kind, framebuffer ?? target?.framebuffer ?? null);
  view = new GltfView(gl);
}

window.refractRender = async ({ scene: sceneUrl, environment, sceneEnvironment, variant, width, height, hideRefractor, without = [] }) => {
  // This page leaves none of the engine's behaviours out (engines/render.mjs's DEPARTURES).
  if (without.length > 0) throw new Error(`without: The glTF Sample Viewer leaves nothing out here, got ${without.join(', ')}`);
  if (view === null) setUp();
  canvas.width = width;
  canvas.height = height;
  floatTarget(width, height);

  const state = view.createState();
  // Not `view.createResourceLoader()`: it starts the KTX and Draco decoders, whose libraries
  // the exported scenes never need (and the npm build expects as page globals).
  const loader = new ResourceLoader(view, '/engines/node_modules/@khronosgroup/gltf-viewer/dist/libs/');
  state.gltf = await loader.loadGltf(sceneUrl);
  if (!state.gltf.cameras || state.gltf.cameras.length === 0) throw new Error(`${sceneUrl} has no camera`);
  state.sceneIndex = state.gltf.scene ?? 0;
  state.cameraIndex = 0;
  if (hideRefractor) {
    const refractors = state.gltf.nodes.filter((n) => /^refractor(-\d+)?$/.test(n.name ?? ''));
    if (refractors.length === 0) throw new Error(`${sceneUrl} has no node named refractor`);
    // The viewer draws the nodes with a mesh: a refractor without one is not drawn.
    for (const n of refractors) n.mesh = undefined;
  }
  const p = state.renderingParameters;
  p.toneMap = GltfState.ToneMaps.NONE;
  p.exposure = 1.0;
  p.clearColor = [0, 0, 0, 1];
  p.usePunctual = false;
  p.internalMSAA = 1;
  p.blurEnvironmentMap = false;
  p.environmentRotation = ENVIRONMENT_ROTATION_DEG;
  // The renderer binds an environment's maps (and its GGX look-up table) to every PBR draw,
  // used or not: a frame without image-based light (the position-coded one) still gets the
  // scene's environment, with `useIBL` off (its light scaled by 0) and no background.
  const { file, key } = sceneEnvironment;
  if (!environments.has(key)) {
    environments.set(key, await loader.loadEnvironment(file, { lut_sheen_E_file: SHEEN_LUT }));
  }
  state.environment = environments.get(key);
  p.useIBL = Boolean(environment);
  p.renderEnvironmentMap = Boolean(environment);
  // No light but the environment's: not the key and fill lights the viewer adds without it.
  p.useDirectionalLightsWithDisabledIBL = false;

  // The first frame compiles the programs; the second is read back and timed, a one-pixel read
  // waiting for each (Chromium's `gl.finish()` returns before the GPU process has drawn).
  const pixel = new Float32Array(4);
  const readPixel = () => {
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, target.framebuffer);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.FLOAT, pixel);
  };
  view.renderFrame(state, width, height);
  readPixel();
  const start = performance.now();
  view.renderFrame(state, width, height);
  readPixel();
  const ms = performance.now() - start;

  const rows = new Float32Array(width * height * 4);
  gl.bindFramebuffer(gl.READ_FRAMEBUFFER, target.framebuffer);
  gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, rows);
  for (let i = 0; i < rows.length; i++) {
    if (i % 4 !== 3) rows[i] = Math.pow(Math.max(rows[i], 0), GAMMA);
  }
  return {
    engine: 'gltf-viewer',
    version: VERSION,
    width,
    height,
    ms,
    settings: {
      variant,
      toneMap: 'NONE',
      exposure: 1.0,
      outputCurve: `pow(c, 1/${GAMMA}) in the viewer, inverted here`,
      renderTarget: 'RGBA32F in place of the canvas, no MSAA',
      internalMSAA: 1,
      usePunctual: false,
      useIBL: Boolean(environment),
      useDirectionalLightsWithDisabledIBL: false,
      blurEnvironmentMap: false,
      clearColor: [0, 0, 0, 1],
      environmentRotationDeg: environment ? ENVIRONMENT_ROTATION_DEG : null,
      sheenLut: 'one black pixel (not in the package; no exported material has sheen)',
      hideRefractor: Boolean(hideRefractor),
      webgl: gl.getParameter(gl.VERSION),
    },
    pixels: topDownBase64(rows, width, height),
  };
};
