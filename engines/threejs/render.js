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

// One renderer for every request of the page (render.mjs serves many scenes from one page):
// three.js keeps the PMREM it prefilters from an environment texture for as long as both
// live, and the environments below live as long as the page.
let renderer = null;
// The environment textures by the content of their file (render.mjs's `environmentKey`).
const environments = new Map();

// What `without` (engines/render.mjs's DEPARTURES) leaves out of the glass, as edits of three.js's
// shader chunks: [chunk, text, replacement]. Each text must be found, so a three.js whose shader
// has moved fails loudly instead of measuring nothing. Only the glass's program is edited.
const CHUNK_EDITS = {
  // The environment's specular reflection (its PMREM along the reflected ray, weighted by the
  // split-sum BRDF). The material's `envMapIntensity` would not do: under `scene.environment`
  // three.js sets the uniform from `scene.environmentIntensity`.
  reflection: [
    'lights_fragment_maps',
    'radiance += iblRadiance;',
    '/* refract: the environment reflection left out */',
  ],
  // The `(1 - F)` weight of the environment BRDF on the transmitted light.
  'fresnel-weight': [
    'transmission_pars_fragment',
    'return vec4( ( 1.0 - F ) * attenuatedColor,',
    'return vec4( attenuatedColor,',
  ],
  // The mip-level bicubic read at the roughness LOD (roughness 0 is raised to 0.045 plus the
  // normal's screen-space change): the nearest texel of level 0 instead, clamped to the target.
  'filtered-read': [
    'transmission_pars_fragment',
    'return textureBicubic( transmissionSamplerMap, fragCoord.xy, lod );',
    'return texelFetch( transmissionSamplerMap, clamp( ivec2( floor( fragCoord.xy * transmissionSamplerSize ) ), ivec2( 0 ), ivec2( transmissionSamplerSize ) - 1 ), 0 );',
  ],
};

/// Leaves `without`'s behaviours out of every transmissive material of `root`.
function leaveOut(root, without) {
  if (without.length === 0) return;
  const chunks = new Map();
  for (const departure of without) {
    const [name, text, replacement] = CHUNK_EDITS[departure];
    const chunk = chunks.get(name) ?? THREE.ShaderChunk[name];
    if (!chunk.includes(text)) throw new Error(`without ${departure}: three.js ${THREE.REVISION}'s ${name} has no "${text}"`);
    chunks.set(name, chunk.replace(text, replacement));
  }
  const key = [...without].sort().join(',');
  root.traverse((object) => {
    for (const material of [object.material ?? []].flat()) {
      if (!(material.transmission > 0)) continue;
      material.onBeforeCompile = (shader) => {
        for (const [name, chunk] of chunks) {
          const include = `#include <${name}>`;
          if (!shader.fragmentShader.includes(include)) throw new Error(`three.js ${THREE.REVISION}: the glass's fragment shader has no ${include}`);
          shader.fragmentShader = shader.fragmentShader.replace(include, chunk);
        }
      };
      material.customProgramCacheKey = () => key;
    }
  });
}

window.refractRender = async ({ scene: sceneUrl, environment, environmentKey, variant, width, height, hideRefractor, without = [] }) => {
  if (renderer === null) {
    const canvas = document.createElement('canvas');
    renderer = new THREE.WebGLRenderer({ canvas, antialias: false, alpha: false });
  }
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
  renderer.setClearColor(0x000000, 1);
  renderer.transmissionResolutionScale = 1;

  const gltf = await new GLTFLoader().loadAsync(sceneUrl);
  leaveOut(gltf.scene, without);
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
    if (!environments.has(environmentKey)) {
      const loaded = await new HDRLoader().setDataType(THREE.FloatType).loadAsync(environment);
      loaded.mapping = THREE.EquirectangularReflectionMapping;
      environments.set(environmentKey, loaded);
    }
    const map = environments.get(environmentKey);
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
  // The first frame compiles the programs and builds the PMREM of the environment (once per
  // environment); the second is the one read back and timed. Chromium's `gl.finish()` returns
  // before the GPU process has drawn, so a one-pixel read waits for each frame instead.
  const pixel = new Float32Array(4);
  renderer.render(scene, camera);
  renderer.readRenderTargetPixels(target, 0, 0, 1, 1, pixel);
  const start = performance.now();
  renderer.render(scene, camera);
  renderer.readRenderTargetPixels(target, 0, 0, 1, 1, pixel);
  const ms = performance.now() - start;

  const rows = new Float32Array(width * height * 4);
  renderer.readRenderTargetPixels(target, 0, 0, width, height, rows);
  const info = renderer.getContext().getParameter(renderer.getContext().VERSION);
  // What this request made; the renderer and the environments stay for the next one.
  renderer.setRenderTarget(null);
  target.dispose();
  gltf.scene.traverse((object) => {
    object.geometry?.dispose();
    for (const material of [object.material ?? []].flat()) {
      for (const value of Object.values(material)) if (value?.isTexture) value.dispose();
      material.dispose();
    }
  });
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
      without,
      webgl: info,
    },
    pixels: topDownBase64(rows, width, height),
  };
};
