// Babylon.js renders a scene of `refract export --format gltf` into a float render target and
// hands the pixels back (engines/README.md). Every setting that changes pixels is pinned here
// and returned in `settings`.
// `BABYLON` is the global of the UMD builds index.html loads (with the glTF loader).
import { topDownBase64 } from '../common.js';

const { BABYLON } = window;

// Babylon's lat-long lookup of an HDR in a right-handed scene is a half turn about +y from
// refract's `u = atan2(x, -z) / 2 pi`: rotating the environment by pi turns one into the other
// (held by the background test, crates/refract-engines/tests/engines.rs; a quarter turn either
// way or none is off by 1.4 to 1.9 in the decoded direction).
const ENVIRONMENT_ROTATION_Y = Math.PI;
// The cube faces Babylon resamples the lat-long map into (HDRCubeTexture).
const CUBE_SIZE = 512;
// The default skybox's edge: far behind every object of refract's scenes.
const SKYBOX_EDGE = 1e4;

// One engine for every request of the page (render.mjs serves many scenes from one page), and
// one Babylon scene per environment (render.mjs's `environmentKey`; `null`: none): the scene
// keeps its prefiltered environment and its skybox, and each request loads its glTF into it
// and disposes what it loaded when done.
let engine = null;
const stages = new Map();

// The scene for an environment, with the environment prefiltered and the skybox made (before
// any glTF: one made later is not drawn into the transmission helper's target, which the glass
// reads; nor is one beyond the camera's far plane, see below).
async function stage(environment, environmentKey) {
  if (stages.has(environmentKey)) return stages.get(environmentKey);
  const scene = new BABYLON.Scene(engine);
  // glTF is right-handed; so is refract. A right-handed scene keeps the loader from mirroring
  // the asset under a `__root__` node.
  scene.useRightHandedSystem = true;
  scene.clearColor = new BABYLON.Color4(0, 0, 0, 1);
  // Linear output, no tone mapping, no clamp: image processing "by post-process" with no
  // post-process attached leaves the materials' linear colour as it is.
  scene.imageProcessingConfiguration.applyByPostProcess = true;
  scene.imageProcessingConfiguration.toneMappingEnabled = false;
  scene.imageProcessingConfiguration.skipFinalColorClamp = true;
  if (environment) {
    const environmentTexture = new BABYLON.HDRCubeTexture(environment, scene, CUBE_SIZE, false, true, false, true);
    environmentTexture.rotationY = ENVIRONMENT_ROTATION_Y;
    await new Promise((resolve, reject) => {
      environmentTexture.onLoadObservable.addOnce(resolve);
      setTimeout(() => reject(new Error(`${environment}: not loaded in 120 s`)), 120000);
    });
    scene.environmentTexture = environmentTexture;
    // The skybox samples a clone of the texture, which does not keep the rotation.
    const skybox = scene.createDefaultSkybox(environmentTexture, true, SKYBOX_EDGE, 0, false);
    skybox.material.reflectionTexture.rotationY = ENVIRONMENT_ROTATION_Y;
  }
  stages.set(environmentKey, scene);
  return scene;
}

// What `without` (engines/render.mjs's DEPARTURES) leaves out of the glass, as edits of the PBR
// fragment shader's final GLSL (after Babylon has resolved its includes): [text, replacement]
// pairs.
// Each text must be found, so a Babylon.js whose shader has moved fails loudly instead of
// measuring nothing. Only the glass's program is edited.
const FRAGMENT_EDITS = {
  // The environment's specular reflection (its prefiltered cube along the reflected ray,
  // weighted by the BRDF lookup table), `pbrBlockFinalLitComponents`.
  reflection: [[
    'vec3 finalRadianceScaled=finalRadiance*vLightingIntensity.z;',
    'vec3 finalRadianceScaled=vec3(0.0);',
  ]],
  // Babylon weights the refracted light twice: by `1 - specularEnvironmentReflectance`
  // (`pbrBlockSubSurface`), and by the surface albedo it tints the refraction with (the loader
  // sets `useAlbedoToTintRefraction`), which its legacy energy conservation scales by
  // `1 - F0` (`pbrBlockReflectivity`; the glass's only use of that albedo).
  'fresnel-weight': [[
    'outParams.finalRefraction*=vec3(1.0)-vSpecularEnvironmentReflectance;',
    '',
  ], [
    'outParams.surfaceAlbedo=baseColor.rgb*(vec3(1.0)-vec3(dielectricF0)*surfaceReflectivityColor)*(1.0-outParams.metallic);',
    'outParams.surfaceAlbedo=baseColor.rgb*(1.0-outParams.metallic);',
  ]],
  // The bilinear read of the transmission helper's target at the roughness LOD: the nearest
  // texel of level 0 instead, clamped to the target, `pbrBlockSubSurface`.
  'filtered-read': [[
    'environmentRefraction=sampleRefractionLod(refractionSampler,refractionCoords,requestedRefractionLOD);',
    'environmentRefraction=texelFetch(refractionSampler,clamp(ivec2(floor(refractionCoords*vec2(textureSize(refractionSampler,0)))),ivec2(0),textureSize(refractionSampler,0)-ivec2(1)),0);',
  ]],
};

/// Leaves `without`'s behaviours out of every refracting PBR material of `materials`: under a
/// shader name of its own (a copy of `pbr`, so that Babylon's effect cache, keyed by name and
/// defines, does not hand back the unedited program) whose final fragment code is edited.
/// Returns the edits that found no text, after the frame that compiled them.
function leaveOut(materials, without) {
  const missing = new Set();
  if (without.length === 0) return missing;
  const key = [...without].sort().join('-');
  const name = `pbrRefractWithout-${key}`;
  const store = BABYLON.ShaderStore.ShadersStore;
  store[`${name}VertexShader`] = store.pbrVertexShader;
  store[`${name}PixelShader`] = store.pbrPixelShader;
  for (const material of materials) {
    if (!material.subSurface?.isRefractionEnabled) continue;
    material.customShaderNameResolve = (shaderName, uniforms, uniformBuffers, samplers, defines, attributes, options) => {
      options.processFinalCode = (type, code) => {
        if (type !== 'fragment') return code;
        let edited = code;
        for (const departure of without) {
          for (const [text, replacement] of FRAGMENT_EDITS[departure]) {
            if (!edited.includes(text)) missing.add(departure);
            edited = edited.replace(text, replacement);
          }
        }
        return edited;
      };
      return name;
    };
  }
  return missing;
}

// What a scene holds, by kind: what a request loaded is what it holds after minus before.
const HOLDINGS = ['meshes', 'materials', 'textures', 'cameras', 'transformNodes', 'geometries', 'lights'];
const holdings = (scene) => Object.fromEntries(HOLDINGS.map((kind) => [kind, new Set(scene[kind])]));

window.refractRender = async ({ scene: sceneUrl, environment, environmentKey, variant, width, height, hideRefractor, without = [] }) => {
  if (engine === null) {
    const canvas = document.createElement('canvas');
    canvas.width = width;
    canvas.height = height;
    engine = new BABYLON.Engine(canvas, false, { preserveDrawingBuffer: true, adaptToDeviceRatio: false });
  }
  engine.setHardwareScalingLevel(1);
  engine.setSize(width, height);
  const scene = await stage(environment, environment ? environmentKey : null);
  const before = holdings(scene);

  await BABYLON.AppendSceneAsync(sceneUrl, scene);
  const missing = leaveOut(scene.materials.filter((m) => !before.materials.has(m)), without);
  const camera = scene.cameras.find((c) => !before.cameras.has(c));
  if (!camera) throw new Error(`${sceneUrl} has no camera`);
  scene.activeCamera = camera;
  // The skybox's corners lie at 0.87 of its edge; the far plane goes beyond them (the export's is
  // refract's, 100), or the transmission helper's target leaves the sky out. Depth precision
  // is all the far plane changes here.
  if (environment) camera.maxZ = Math.max(camera.maxZ, 2 * SKYBOX_EDGE);
  if (hideRefractor) {
    // Every refractor: nodes `refractor`, `refractor-1`, ... (refract's export).
    const refractors = [...scene.meshes, ...scene.transformNodes]
      .filter((node) => /^refractor(-\d+)?$/.test(node.name));
    if (refractors.length === 0) throw new Error(`${sceneUrl} has no node named refractor`);
    for (const node of refractors) {
      for (const mesh of [node, ...node.getChildMeshes?.() ?? []]) mesh.setEnabled(false);
    }
  }
  // The glTF loader's transmission helper renders the opaque objects into its own target,
  // 1024 x 1024, 4x MSAA, half float by default; pinned to the frame's size, one sample, float.
  const helper = scene._transmissionHelper;
  if (helper) {
    // The helper sorts each new mesh into its opaque or transparent list a tick later
    // (`Tools.SetImmediate`); a frame rendered before that reads an empty target.
    const sorted = () => helper._opaqueMeshesCache.length + helper._transparentMeshesCache.length
      >= scene.meshes.filter((mesh) => mesh.material).length;
    for (let tick = 0; tick < 100 && !sorted(); tick++) await new Promise((r) => setTimeout(r, 10));
    if (!sorted()) throw new Error('the transmission helper did not sort the meshes in 1 s');
    // The helper takes any new `renderSize` object for a new size and remakes its target; kept
    // when the size is the same, the target stays the one the scene's glass already reads.
    const size = helper._options.renderSize;
    helper.updateOptions({
      renderSize: size?.width === width && size?.height === height ? size : { width, height },
      samples: 1,
      renderTargetTextureType: BABYLON.Constants.TEXTURETYPE_FLOAT,
    });
  }

  const target = new BABYLON.RenderTargetTexture('refract-frame', { width, height }, scene, {
    generateMipMaps: false,
    type: BABYLON.Constants.TEXTURETYPE_FLOAT,
    samplingMode: BABYLON.Constants.TEXTURE_NEAREST_SAMPLINGMODE,
    samples: 1,
  });
  camera.outputRenderTarget = target;
  await scene.whenReadyAsync();
  // The first frame compiles the programs; the second is the one read back and timed.
  // Chromium's `gl.finish()` returns before the GPU process has drawn, so a one-pixel read waits
  // for each frame instead.
  const waitForFrame = () => target.readPixels(0, 0, null, true, false, 0, 0, 1, 1);
  scene.render();
  await waitForFrame();
  const start = performance.now();
  scene.render();
  await waitForFrame();
  const ms = performance.now() - start;
  const rows = await target.readPixels(0, 0, null, true, false);
  if (!(rows instanceof Float32Array) || rows.length !== width * height * 4) {
    throw new Error(`read back ${rows?.length} values, expected ${width * height * 4} floats`);
  }
  const gl = engine._gl;
  const webgl = gl.getParameter(gl.VERSION);
  // What this request loaded, in the order that leaves nothing pointing at a disposed object;
  // the stage's environment, skybox, transmission helper (with its target) and the BRDF lookup
  // texture the first PBR material made for the scene stay.
  camera.outputRenderTarget = null;
  target.dispose();
  const loaded = (kind) => scene[kind].filter((item) => !before[kind].has(item));
  const kept = new Set([helper?.getOpaqueTarget(), scene.environmentBRDFTexture]);
  for (const mesh of loaded('meshes')) mesh.dispose(true, false);
  for (const item of [...loaded('transformNodes'), ...loaded('cameras'), ...loaded('lights')]) item.dispose();
  for (const material of loaded('materials')) material.dispose(false, false);
  for (const texture of loaded('textures')) if (!kept.has(texture)) texture.dispose();
  for (const geometry of loaded('geometries')) geometry.dispose();
  if (missing.size > 0) throw new Error(`without ${[...missing].join(', ')}: Babylon.js ${BABYLON.Engine.Version}'s PBR fragment shader has no text to edit`);
  return {
    engine: 'babylon',
    version: BABYLON.Engine.Version,
    width,
    height,
    ms,
    settings: {
      variant,
      hardwareScalingLevel: 1,
      antialias: false,
      imageProcessing: 'applyByPostProcess, no post-process: linear, no tone mapping, no clamp',
      renderTarget: 'TEXTURETYPE_FLOAT RGBA, no MSAA',
      transmissionTarget: helper ? `${width}x${height}, 1 sample, float, mipmapped` : null,
      useRightHandedSystem: true,
      clearColor: [0, 0, 0, 1],
      environment: environment ? `HDRCubeTexture ${CUBE_SIZE}, default skybox (edge ${SKYBOX_EDGE}) made before the glTF, camera far ${camera.maxZ}, rotationY ${ENVIRONMENT_ROTATION_Y}` : null,
      hideRefractor: Boolean(hideRefractor),
      without,
      webgl,
    },
    pixels: topDownBase64(rows, width, height),
  };
};
