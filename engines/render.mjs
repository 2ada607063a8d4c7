// Renders scenes exported by `refract export --format gltf` with a real engine, in headless
// Chromium driven over the DevTools protocol (puppeteer-core), and writes each frame as linear
// float RGBA (little-endian f32, rows from the top) with its metadata as JSON.
//
// One scene:
//   node engines/render.mjs --engine threejs --scene DIR --variants color,position \
//        --width W --height H --out DIR [--hide-refractor] [--without LIST] [--browser PATH]
// writes OUT/<variant>.f32 for each variant and prints one JSON line: an array of
// { engine, version, width, height, settings, ms }, one per variant.
//
// Many scenes, one browser (what `refract_engines::EngineSession` runs):
//   node engines/render.mjs --engine threejs --serve [--browser PATH]
// reads one request per line from standard input, { scene, variants, width, height, out,
// hideRefractor, without } with the meanings of the options above, and answers each with one line,
// { frames: [...] } (the array above) or { error: "..." }; it closes the browser and exits at
// the end of the input. The page stays open between requests, so an engine prefilters an
// environment it has seen before only once (engines/README.md).
//
// The page of each engine is engines/<engine>/index.html; it defines
// `window.refractRender(request)` (see engines/README.md for the request and the reply).
// Every file the page loads is served from disk by request interception under one origin:
// /engines/... from this directory (node_modules included), /scene/<k>/... from the k-th
// request's scene directory.

import { createHash } from 'node:crypto';
import { readFile, writeFile } from 'node:fs/promises';
import path from 'node:path';
import { createInterface } from 'node:readline';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';
import puppeteer from 'puppeteer-core';

const ENGINES = ['threejs', 'babylon', 'gltf-viewer'];
const VARIANTS = ['color', 'position'];
// Behaviours of an engine's glass a request may leave out (`without`), to measure each one's share
// of the engine's difference from its re-implementation (docs/engines.md); a page that cannot
// leave one out throws.
const DEPARTURES = ['reflection', 'fresnel-weight', 'filtered-read'];
const MAX_SIDE = 4096;
const ORIGIN = 'http://refract.invalid';
const here = path.dirname(fileURLToPath(import.meta.url));

function fail(message) {
  process.stderr.write(`render.mjs: ${message}\n`);
  process.exit(2);
}

const { values: args } = parseArgs({
  options: {
    engine: { type: 'string' },
    serve: { type: 'boolean', default: false },
    scene: { type: 'string' },
    variants: { type: 'string', default: 'color' },
    width: { type: 'string' },
    height: { type: 'string' },
    out: { type: 'string' },
    'hide-refractor': { type: 'boolean', default: false },
    without: { type: 'string', default: '' },
    browser: { type: 'string', default: process.env.REFRACT_CHROMIUM ?? 'chromium' },
  },
});
if (!ENGINES.includes(args.engine)) fail(`--engine: expected one of ${ENGINES.join(', ')}, got ${args.engine}`);

/// A request with its fields checked: the error names the field and what it takes.
function checkedRequest(request) {
  const { scene, variants, width, height, out, hideRefractor, without = [] } = request;
  if (typeof scene !== 'string' || scene === '') throw new Error('scene: the directory refract export --format gltf wrote');
  if (typeof out !== 'string' || out === '') throw new Error('out: the directory to write the frames into');
  if (!Array.isArray(variants) || variants.length === 0) throw new Error('variants: expected color and/or position');
  for (const variant of variants) {
    if (!VARIANTS.includes(variant)) throw new Error(`variants: expected color and/or position, got ${variant}`);
  }
  for (const [side, n] of [['width', width], ['height', height]]) {
    if (!Number.isInteger(n) || n < 1 || n > MAX_SIDE) throw new Error(`${side}: expected an integer in 1..=${MAX_SIDE}, got ${n}`);
  }
  if (!Array.isArray(without)) throw new Error(`without: expected a list of ${DEPARTURES.join(', ')}`);
  for (const departure of without) {
    if (!DEPARTURES.includes(departure)) throw new Error(`without: expected ${DEPARTURES.join(', ')}, got ${departure}`);
  }
  return { scene: path.resolve(scene), variants, width, height, out, hideRefractor: Boolean(hideRefractor), without };
}

const CONTENT_TYPES = {
  '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
  '.gltf': 'model/gltf+json', '.bin': 'application/octet-stream', '.png': 'image/png',
  '.hdr': 'application/octet-stream', '.wasm': 'application/wasm',
};

// The scene directory of each request, by the k of its URLs (/scene/<k>/...).
const sceneDirs = [];

/// The file behind a URL of ORIGIN, or null outside the served trees.
function fileOf(url) {
  const { pathname } = new URL(url);
  let root = null;
  let rest = null;
  if (pathname.startsWith('/engines/')) {
    [root, rest] = [here, pathname.slice('/engines/'.length)];
  } else {
    const scene = /^\/scene\/(\d+)\/(.*)$/.exec(pathname);
    if (scene && sceneDirs[Number(scene[1])] !== undefined) [root, rest] = [sceneDirs[Number(scene[1])], scene[2]];
  }
  if (root === null) return null;
  const file = path.resolve(root, decodeURIComponent(rest));
  return file.startsWith(root + path.sep) ? file : null;
}

// A page call may take minutes: the glTF Sample Viewer prefilters an environment in about 80 s
// on SwiftShader alone, several times that with other browsers on the same cores (puppeteer's
// default of 180 s failed so in CI).
const PROTOCOL_TIMEOUT_MS = 20 * 60 * 1000;

const browser = await puppeteer.launch({
  executablePath: args.browser,
  headless: true,
  protocolTimeout: PROTOCOL_TIMEOUT_MS,
  args: [
    '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--ignore-gpu-blocklist', '--enable-webgl', '--disable-extensions',
  ],
}).catch((err) => fail(`cannot start ${args.browser}: ${err.message}`));

// What the page printed since the last request began: the context of an error.
let consoleLines = [];
const page = await browser.newPage();
page.on('console', (message) => consoleLines.push(`${message.type()}: ${message.text()}`));
page.on('pageerror', (err) => consoleLines.push(`pageerror: ${err.message}`));
await page.setRequestInterception(true);
page.on('request', async (request) => {
  const file = request.url().startsWith(ORIGIN) ? fileOf(request.url()) : null;
  if (file === null) return request.respond({ status: 404, body: '' });
  try {
    const body = await readFile(file);
    const type = CONTENT_TYPES[path.extname(file)] ?? 'application/octet-stream';
    await request.respond({ status: 200, contentType: type, body });
  } catch {
    await request.respond({ status: 404, body: '' });
  }
});
await page.goto(`${ORIGIN}/engines/${args.engine}/index.html`, { waitUntil: 'load' });
await page.waitForFunction('typeof window.refractRender === "function"', { timeout: 30000 })
  .catch(async () => {
    await browser.close();
    fail(`the ${args.engine} page did not load:\n${consoleLines.join('\n')}`);
  });

/// Renders every variant of one checked request; returns the replies without their pixels.
async function render(request) {
  consoleLines = [];
  const k = sceneDirs.push(request.scene) - 1;
  // The environment's content names it: a page keeps what it made of an environment (three.js's
  // PMREM, Babylon's prefiltered cube) under this key and reuses it for the next scene with the
  // same file.
  const environmentKey = createHash('sha256')
    .update(await readFile(path.join(request.scene, 'environment.hdr')))
    .digest('hex');
  const replies = [];
  for (const variant of request.variants) {
    const coded = variant === 'position';
    let reply;
    try {
      reply = await page.evaluate((pageRequest) => window.refractRender(pageRequest), {
        scene: `/scene/${k}/${coded ? 'position-coded.gltf' : 'scene.gltf'}`,
        environment: coded ? null : `/scene/${k}/environment.hdr`,
        environmentKey: coded ? null : environmentKey,
        // The scene's environment for every variant: a page that must bind one even to a frame
        // without its light (the glTF Sample Viewer) loads it from here.
        sceneEnvironment: { file: `/scene/${k}/environment.hdr`, key: environmentKey },
        variant,
        width: request.width,
        height: request.height,
        hideRefractor: request.hideRefractor,
        without: request.without,
      });
    } catch (err) {
      throw new Error(`${args.engine} failed: ${err.message}\n${consoleLines.join('\n')}`);
    }
    const pixels = Buffer.from(reply.pixels, 'base64');
    const expected = request.width * request.height * 16;
    if (pixels.length !== expected) throw new Error(`${args.engine} returned ${pixels.length} bytes, expected ${expected}`);
    await writeFile(path.join(request.out, `${variant}.f32`), pixels);
    delete reply.pixels;
    replies.push(reply);
  }
  return replies;
}

try {
  if (args.serve) {
    for await (const line of createInterface({ input: process.stdin, crlfDelay: Infinity })) {
      if (line.trim() === '') continue;
      let answer;
      try {
        answer = { frames: await render(checkedRequest(JSON.parse(line))) };
      } catch (err) {
        answer = { error: err.message };
      }
      process.stdout.write(`${JSON.stringify(answer)}\n`);
    }
  } else {
    let request;
    try {
      request = checkedRequest({
        scene: args.scene,
        variants: args.variants.split(','),
        width: Number(args.width),
        height: Number(args.height),
        out: args.out,
        hideRefractor: args['hide-refractor'],
        without: args.without === '' ? [] : args.without.split(','),
      });
    } catch (err) {
      fail(`--${err.message}`);
    }
    const replies = await render(request).catch((err) => fail(err.message));
    process.stdout.write(`${JSON.stringify(replies)}\n`);
  }
} finally {
  await browser.close();
}
