// Renders a scene exported by `refract export --format gltf` with a real engine, in headless
// Chromium driven over the DevTools protocol (puppeteer-core), and writes the frame as linear
// float RGBA (little-endian f32, rows from the top) with its metadata as JSON.
//
//   node engines/render.mjs --engine threejs --scene DIR --variants color,position \
//        --width W --height H --out DIR [--hide-refractor] [--browser PATH]
//
// Writes OUT/<variant>.f32 for each variant, all rendered in one browser session, and prints
// one JSON line: an array of { engine, version, width, height, settings, ms }, one per variant.
// The page of each engine is engines/<engine>/index.html; it defines
// `window.refractRender(request)` (see engines/README.md for the request and the reply).
// Every file the page loads is served from disk by request interception under one origin:
// /engines/... from this directory (node_modules included), /scene/... from --scene.

import { readFile, writeFile } from 'node:fs/promises';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';
import puppeteer from 'puppeteer-core';

const ENGINES = ['threejs', 'babylon'];
const ORIGIN = 'http://refract.invalid';
const here = path.dirname(fileURLToPath(import.meta.url));

function fail(message) {
  process.stderr.write(`render.mjs: ${message}\n`);
  process.exit(2);
}

const { values: args } = parseArgs({
  options: {
    engine: { type: 'string' },
    scene: { type: 'string' },
    variants: { type: 'string', default: 'color' },
    width: { type: 'string' },
    height: { type: 'string' },
    out: { type: 'string' },
    'hide-refractor': { type: 'boolean', default: false },
    browser: { type: 'string', default: process.env.REFRACT_CHROMIUM ?? 'chromium' },
  },
});
if (!ENGINES.includes(args.engine)) fail(`--engine: expected one of ${ENGINES.join(', ')}, got ${args.engine}`);
const variants = args.variants.split(',');
for (const variant of variants) {
  if (!['color', 'position'].includes(variant)) fail(`--variants: expected color and/or position, got ${variant}`);
}
for (const side of ['width', 'height']) {
  const n = Number(args[side]);
  if (!Number.isInteger(n) || n < 1 || n > 4096) fail(`--${side}: expected an integer in 1..=4096, got ${args[side]}`);
}
if (!args.scene) fail('--scene: the directory refract export --format gltf wrote');
if (!args.out) fail('--out: the directory to write the frames into');
const width = Number(args.width);
const height = Number(args.height);
const sceneDir = path.resolve(args.scene);

const CONTENT_TYPES = {
  '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
  '.gltf': 'model/gltf+json', '.bin': 'application/octet-stream', '.png': 'image/png',
  '.hdr': 'application/octet-stream', '.wasm': 'application/wasm',
};

/// The file behind a URL of ORIGIN, or null outside the two served trees.
function fileOf(url) {
  const { pathname } = new URL(url);
  const [root, prefix] = pathname.startsWith('/engines/') ? [here, '/engines/']
    : pathname.startsWith('/scene/') ? [sceneDir, '/scene/'] : [null, null];
  if (root === null) return null;
  const file = path.resolve(root, decodeURIComponent(pathname.slice(prefix.length)));
  return file.startsWith(root + path.sep) ? file : null;
}

const browser = await puppeteer.launch({
  executablePath: args.browser,
  headless: true,
  args: [
    '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--ignore-gpu-blocklist', '--enable-webgl', '--disable-extensions',
  ],
}).catch((err) => fail(`cannot start ${args.browser}: ${err.message}`));

try {
  const page = await browser.newPage();
  const consoleLines = [];
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
    .catch(() => fail(`the ${args.engine} page did not load:\n${consoleLines.join('\n')}`));
  const replies = [];
  for (const variant of variants) {
    const reply = await page.evaluate((request) => window.refractRender(request), {
      scene: `/scene/${variant === 'position' ? 'position-coded.gltf' : 'scene.gltf'}`,
      environment: variant === 'position' ? null : '/scene/environment.hdr',
      variant,
      width,
      height,
      hideRefractor: args['hide-refractor'],
    }).catch((err) => fail(`${args.engine} failed: ${err.message}\n${consoleLines.join('\n')}`));
    const pixels = Buffer.from(reply.pixels, 'base64');
    if (pixels.length !== width * height * 16) fail(`${args.engine} returned ${pixels.length} bytes, expected ${width * height * 16}`);
    await writeFile(path.join(args.out, `${variant}.f32`), pixels);
    delete reply.pixels;
    replies.push(reply);
  }
  process.stdout.write(`${JSON.stringify(replies)}\n`);
} finally {
  await browser.close();
}
