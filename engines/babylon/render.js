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

window.refractRender = async ({ scene: sceneUrl, environment, variant, width, height, hideRefractor }) => {
  const canvas = document.createElement('canvas');
  canvas.width = width;
  canvas.height = height;
  const engine = new BABYLON.Engine(canvas, false, { preserveDrawingBuffer: true, adaptToDeviceRatio: false });
  engine.setHardwareScalingLevel(1);
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

  let environmentTexture = null;
  if (environment) {
    environmentTexture = new BABYLON.HDRCubeTexture(environment, scene, CUBE_SIZE, false, true, false, true);
    environmentTexture.rotationY = ENVIRONMENT_ROTATION_Y;
    await new Promise((resolve, reject) => {
      environmentTexture.onLoadObservable.addOnce(resolve);
      setTimeout(() => reject(new Error(`${environment}: not loaded in 60 s`)), 60000);
    });
    scene.environmentTexture = environmentTexture;
    // The skybox samples a clone of the texture, which does not keep the rotation. It is made
    // before the glTF is loaded: one made later is not drawn into the transmission helper's
    // target, which the glass reads (nor is one beyond the camera's far plane: see below).
    const skybox = scene.createDefaultSkybox(environmentTexture, true, SKYBOX_EDGE, 0, false);
    skybox.material.reflectionTexture.rotationY = ENVIRONMENT_ROTATION_Y;
  }

  await BABYLON.AppendSceneAsync(sceneUrl, scene);
  const camera = scene.cameras[0];
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
    helper.updateOptions({
      renderSize: { width, height },
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
  scene.render();
  const gl = engine._gl;
  gl.finish();
  const start = performance.now();
  scene.render();
  gl.finish();
  const ms = performance.now() - start;
  const rows = await target.readPixels(0, 0, null, true, false);
  if (!(rows instanceof Float32Array) || rows.length !== width * height * 4) {
    throw new Error(`read back ${rows?.length} values, expected ${width * height * 4} floats`);
  }
  const webgl = gl.getParameter(gl.VERSION);
  engine.dispose();
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
      webgl,
    },
    pixels: topDownBase64(rows, width, height),
  };
};
