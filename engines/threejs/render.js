// three.js renders a scene of `refract export --format gltf` into a float render target and
// hands the pixels back (engines/README.md). Every setting that changes pixels is pinned here
// and returned in `settings`.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { HDRLoader } from 'three/addons/loaders/HDRLoader.js';
import { topDownBase64 } from '../common.js';

// refract's lat-long orientation is u = atan2(x, -z) / 2 pi; three.js's equirectangular lookup
// is u = atan2(z, x) / 2 pi + 1/2, a quarter turn further for every direction: rotating the
// looked-up direction by -pi/2 about +y turns one into the other (held by the background test,
// crates/refract-engines/tests/engines.rs).
const ENVIRONMENT_ROTATION_Y = -Math.PI / 2;

window.refractRender = async ({ scene: sceneUrl, environment, variant, width, height, hideRefractor }) => {
  const canvas = document.createElement('canvas');
  canvas.width = width;
  canvas.height = height;
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, alpha: false });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  renderer.setClearColor(0x000000, 1);
  renderer.transmissionResolutionScale = 1;

  const gltf = await new GLTFLoader().loadAsync(sceneUrl);
  // GLTFLoader's `gltf.scene` is a Group; the background and the environment are a Scene's.
  const scene = new THREE.Scene();
  scene.add(gltf.scene);
  const camera = gltf.cameras[0];
  if (!camera) throw new Error(`${sceneUrl} has no camera`);
  camera.aspect = width / height;
  camera.updateProjectionMatrix();
  // Every refractor: nodes `refractor`, `refractor-1`, ... (refract's export).
  if (hideRefractor) {
    const refractors = [];
    scene.traverse((o) => { if (/^refractor(-\d+)?$/.test(o.name)) refractors.push(o); });
    if (refractors.length === 0) throw new Error(`${sceneUrl} has no node named refractor`);
    for (const o of refractors) o.visible = false;
  }
  if (environment) {
    const map = await new HDRLoader().setDataType(THREE.FloatType).loadAsync(environment);
    map.mapping = THREE.EquirectangularReflectionMapping;
    scene.background = map;
    scene.environment = map;
    scene.backgroundRotation.set(0, ENVIRONMENT_ROTATION_Y, 0);
    scene.environmentRotation.set(0, ENVIRONMENT_ROTATION_Y, 0);
  }

  const target = new THREE.WebGLRenderTarget(width, height, {
    type: THREE.FloatType,
    format: THREE.RGBAFormat,
    colorSpace: THREE.LinearSRGBColorSpace,
    depthBuffer: true,
    samples: 0,
    minFilter: THREE.NearestFilter,
    magFilter: THREE.NearestFilter,
  });
  renderer.setRenderTarget(target);
  // The first frame compiles the programs and builds the PMREM of the environment; the second
  // is the one read back and timed.
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  gl.finish();
  const start = performance.now();
  renderer.render(scene, camera);
  gl.finish();
  const ms = performance.now() - start;

  const rows = new Float32Array(width * height * 4);
  renderer.readRenderTargetPixels(target, 0, 0, width, height, rows);
  const info = renderer.getContext().getParameter(renderer.getContext().VERSION);
  renderer.dispose();
  return {
    engine: 'threejs',
    version: `0.${THREE.REVISION}.0`,
    width,
    height,
    ms,
    settings: {
      variant,
      pixelRatio: 1,
      antialias: false,
      toneMapping: 'NoToneMapping',
      outputColorSpace: 'LinearSRGBColorSpace',
      renderTarget: 'FloatType RGBA, no MSAA',
      transmissionResolutionScale: renderer.transmissionResolutionScale,
      clearColor: [0, 0, 0, 1],
      environmentRotationY: environment ? ENVIRONMENT_ROTATION_Y : null,
      hideRefractor: Boolean(hideRefractor),
      webgl: info,
    },
    pixels: topDownBase64(rows, width, height),
  };
};
