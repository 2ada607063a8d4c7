// refract sweep report: a sortable metrics table and a comparison viewer (reference vs method,
// an A/B slider from the vendored img-comparison-slider, or a flip), zoom and pan in sync,
// display exposure, and the error maps one key away. No network, no dependencies beyond the
// slider.
"use strict";

function sortable(table) {
  const headers = Array.from(table.tHead.rows[0].cells);
  headers.forEach((th, column) => {
    th.addEventListener("click", () => {
      const ascending = !th.classList.contains("asc");
      headers.forEach((h) => h.classList.remove("asc", "desc"));
      th.classList.add(ascending ? "asc" : "desc");
      const body = table.tBodies[0];
      const rows = Array.from(body.rows);
      const key = (row) => {
        const text = row.cells[column].textContent.trim();
        const number = parseFloat(text);
        return Number.isNaN(number) || !/^[-+0-9.]/.test(text) ? text : number;
      };
      rows.sort((a, b) => {
        const x = key(a), y = key(b);
        const order = typeof x === "number" && typeof y === "number"
          ? x - y
          : String(x).localeCompare(String(y));
        return ascending ? order : -order;
      });
      rows.forEach((row) => body.appendChild(row));
    });
  });
}

const viewer = {
  thumbs: [],
  index: 0,
  layer: "image", // image | flip | t2 | miss
  mode: "slider", // slider | flip
  showReference: false,
  exposure: 0, // stops, applied to colour images as displayed
  zoom: 1,
  x: 0,
  y: 0,
};

// Linear colour for the exposure control: RGBE in a double-width PNG held as a data URL by a
// per-image script (refract's images::write_hdr_script), decoded to floats once.
const hdrCache = new Map();

function loadScript(src) {
  return new Promise((resolve, reject) => {
    const script = document.createElement("script");
    script.src = src;
    script.onload = resolve;
    script.onerror = () => reject(new Error(`cannot load ${src}`));
    document.head.append(script);
  });
}

async function loadHdr(src) {
  if (hdrCache.has(src)) return hdrCache.get(src);
  if (!(window.refractHdr && window.refractHdr[src])) await loadScript(src);
  const img = new Image();
  img.src = window.refractHdr[src];
  await img.decode();
  const w = img.naturalWidth / 2, h = img.naturalHeight;
  const canvas = document.createElement("canvas");
  canvas.width = 2 * w;
  canvas.height = h;
  const ctx = canvas.getContext("2d");
  ctx.drawImage(img, 0, 0);
  const bytes = ctx.getImageData(0, 0, 2 * w, h).data;
  const linear = new Float32Array(w * h * 3);
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const m = 4 * (y * 2 * w + x), e = bytes[4 * (y * 2 * w + w + x)];
      const scale = e === 0 ? 0 : Math.pow(2, e - 136);
      const o = 3 * (y * w + x);
      for (let k = 0; k < 3; k++) linear[o + k] = e === 0 ? 0 : (bytes[m + k] + 0.5) * scale;
    }
  }
  const hdr = { w, h, linear };
  hdrCache.set(src, hdr);
  return hdr;
}

// refract_scene::tonemap: Narkowicz's ACES fit, then the sRGB transfer function.
function display(v) {
  const x = Math.max(v, 0);
  const t = Math.min(Math.max((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0), 1);
  const s = t <= 0.0031308 ? 12.92 * t : 1.055 * Math.pow(t, 1 / 2.4) - 0.055;
  return Math.round(255 * s);
}

function drawHdr(canvas) {
  const hdr = canvas.hdr;
  if (!hdr) return;
  const gain = Math.pow(2, viewer.exposure);
  const out = canvas.getContext("2d").createImageData(hdr.w, hdr.h);
  for (let i = 0, n = hdr.w * hdr.h; i < n; i++) {
    out.data[4 * i] = display(gain * hdr.linear[3 * i]);
    out.data[4 * i + 1] = display(gain * hdr.linear[3 * i + 1]);
    out.data[4 * i + 2] = display(gain * hdr.linear[3 * i + 2]);
    out.data[4 * i + 3] = 255;
  }
  canvas.getContext("2d").putImageData(out, 0, 0);
}

function layerSource(thumb) {
  const d = thumb.dataset;
  switch (viewer.layer) {
    case "flip": return d.flip;
    case "t2": return d.t2;
    case "miss": return d.miss || d.image;
    default: return d.image;
  }
}

function applyView() {
  const stage = document.getElementById("stage");
  const transform = `translate(${viewer.x}px, ${viewer.y}px) scale(${viewer.zoom})`;
  stage.querySelectorAll("img, canvas").forEach((el) => {
    el.style.transform = transform;
    // Colour images without linear data get a display-exposure approximation.
    const colour = el.dataset.kind === "colour";
    el.style.filter = colour ? `brightness(${Math.pow(2, viewer.exposure)})` : "none";
    if (el.dataset.kind === "hdr") drawHdr(el);
  });
  const thumb = viewer.thumbs[viewer.index];
  const side = viewer.mode === "flip" ? (viewer.showReference ? "reference" : "method") : "reference | method";
  document.getElementById("bar").innerHTML =
    `<b>${thumb.dataset.title}</b> &nbsp; ${viewer.layer} · ${viewer.mode} (${side}) · exposure ${viewer.exposure >= 0 ? "+" : ""}${viewer.exposure} EV · zoom ${viewer.zoom.toFixed(2)}×<br>` +
    "<kbd>1</kbd> image <kbd>2</kbd> FLIP <kbd>3</kbd> T2 error <kbd>4</kbd> missed objects · " +
    "<kbd>s</kbd> slider <kbd>f</kbd> flip A/B · <kbd>e</kbd>/<kbd>E</kbd> exposure ±1 stop (linear radiance) · " +
    "wheel zoom, shift+drag pan, <kbd>0</kbd> reset · <kbd>←</kbd>/<kbd>→</kbd> previous/next · <kbd>Esc</kbd> close";
}

const DISPLAY_WIDTH = 512;

// An image of the viewer: a canvas of linear colour when `hdr` names its data, else the PNG
// (error maps carry a colour bar: they are scaled by the image width, not the bar's).
function image(src, kind, hdr) {
  if (hdr) {
    const canvas = document.createElement("canvas");
    canvas.dataset.kind = "hdr";
    canvas.style.width = `${DISPLAY_WIDTH}px`;
    loadHdr(hdr).then((data) => {
      canvas.width = data.w;
      canvas.height = data.h;
      canvas.hdr = data;
      drawHdr(canvas);
    }).catch(() => {
      const img = image(src, kind);
      canvas.replaceWith(img);
      applyView();
    });
    return canvas;
  }
  const img = document.createElement("img");
  img.src = src;
  img.dataset.kind = kind;
  img.draggable = false;
  img.style.width = `${DISPLAY_WIDTH}px`;
  img.onload = () => {
    const reference = viewer.referenceWidth || img.naturalWidth;
    img.style.width = `${(DISPLAY_WIDTH * img.naturalWidth) / reference}px`;
  };
  return img;
}

function render() {
  const thumb = viewer.thumbs[viewer.index];
  const stage = document.getElementById("stage");
  stage.textContent = "";
  const methodKind = viewer.layer === "image" || viewer.layer === "miss" ? "colour" : "map";
  const hdr = viewer.layer === "image" ? thumb.dataset.hdr : "";
  const method = image(layerSource(thumb), methodKind, hdr);
  const reference = image(thumb.dataset.reference, "colour", thumb.dataset.referenceHdr);
  // The reference's pixel width sets the scale of every image (maps are wider by their bar).
  const probe = new Image();
  probe.onload = () => { viewer.referenceWidth = probe.naturalWidth; };
  probe.src = thumb.dataset.reference;
  if (viewer.mode === "slider") {
    const slider = document.createElement("img-comparison-slider");
    reference.slot = "first";
    method.slot = "second";
    slider.append(reference, method);
    stage.append(slider);
  } else {
    stage.append(viewer.showReference ? reference : method);
  }
  applyView();
}

function open(index) {
  viewer.index = index;
  document.getElementById("viewer").classList.add("open");
  render();
}

function close() {
  document.getElementById("viewer").classList.remove("open");
}

function key(event) {
  if (!document.getElementById("viewer").classList.contains("open")) return;
  const n = viewer.thumbs.length;
  const layers = { "1": "image", "2": "flip", "3": "t2", "4": "miss" };
  if (layers[event.key]) { viewer.layer = layers[event.key]; render(); return; }
  switch (event.key) {
    case "Escape": close(); return;
    case "s": viewer.mode = "slider"; break;
    case "f":
      if (viewer.mode === "flip") viewer.showReference = !viewer.showReference;
      else { viewer.mode = "flip"; viewer.showReference = false; }
      break;
    case "e": viewer.exposure += 1; applyView(); return;
    case "E": viewer.exposure -= 1; applyView(); return;
    case "0": viewer.zoom = 1; viewer.x = 0; viewer.y = 0; applyView(); return;
    case "ArrowRight": viewer.index = (viewer.index + 1) % n; break;
    case "ArrowLeft": viewer.index = (viewer.index + n - 1) % n; break;
    default: return;
  }
  render();
}

function panAndZoom(stage) {
  stage.addEventListener("wheel", (event) => {
    event.preventDefault();
    const factor = event.deltaY < 0 ? 1.25 : 0.8;
    const rect = stage.querySelector("img")?.getBoundingClientRect();
    if (rect) {
      // Keep the point under the cursor fixed.
      const px = event.clientX - rect.left, py = event.clientY - rect.top;
      viewer.x -= px * (factor - 1);
      viewer.y -= py * (factor - 1);
    }
    viewer.zoom = Math.min(64, Math.max(0.25, viewer.zoom * factor));
    applyView();
  }, { passive: false });
  let drag = null;
  stage.addEventListener("pointerdown", (event) => {
    if (!event.shiftKey) return;
    drag = { x: event.clientX - viewer.x, y: event.clientY - viewer.y };
    event.preventDefault();
    event.stopPropagation();
  }, true);
  window.addEventListener("pointermove", (event) => {
    if (!drag) return;
    viewer.x = event.clientX - drag.x;
    viewer.y = event.clientY - drag.y;
    applyView();
  });
  window.addEventListener("pointerup", () => { drag = null; });
}

// The overview matrix (overview.rs): the metric and backend shown, every cell of that backend
// coloured on one scale (log where the values span more than 20x), light green = lowest.
function cellColour(t) {
  return `hsl(${Math.round(120 * (1 - t))}, 65%, ${Math.round(82 - 8 * t)}%)`;
}

function formatValue(v, metric) {
  if (metric === "t2") return `${v.toFixed(2)}°`;
  if (metric === "ms") return v >= 100 ? v.toFixed(0) : v.toFixed(1);
  return v.toFixed(3);
}

function colourMatrix() {
  const table = document.getElementById("matrix");
  if (!table) return;
  const metric = document.getElementById("metric").value;
  const cells = Array.from(table.querySelectorAll(`.cell[data-backend="${table.dataset.backend}"]`));
  const values = cells.map((c) => parseFloat(c.dataset[metric])).filter(Number.isFinite);
  const lo = Math.min(...values), hi = Math.max(...values);
  const log = lo > 0 && hi / lo > 20;
  const f = (v) => (log ? Math.log(v) : v);
  cells.forEach((cell) => {
    const v = parseFloat(cell.dataset[metric]);
    const label = cell.querySelector(".v");
    if (!Number.isFinite(v)) {
      label.textContent = "–";
      cell.style.background = "#eee";
      return;
    }
    const t = hi > lo ? (f(v) - f(lo)) / (f(hi) - f(lo)) : 0;
    cell.style.background = cellColour(t);
    label.textContent = formatValue(v, metric);
  });
  const scale = document.getElementById("scale");
  if (scale && values.length) {
    const stops = [0, 0.25, 0.5, 0.75, 1].map((t) => `${cellColour(t)} ${100 * t}%`).join(",");
    scale.innerHTML = `${formatValue(lo, metric)} <i style="background:linear-gradient(90deg,${stops})"></i> ${formatValue(hi, metric)}${log ? " (log scale)" : ""}`;
  }
}

function overview() {
  const table = document.getElementById("matrix");
  if (!table) return;
  document.getElementById("metric").addEventListener("change", colourMatrix);
  document.querySelectorAll("input[name=backend]").forEach((radio) =>
    radio.addEventListener("change", () => {
      table.dataset.backend = radio.value;
      colourMatrix();
    }));
  colourMatrix();
  // For tests and scripts: where the matrix ends on the first screen.
  document.body.dataset.matrixBottom = String(Math.round(table.getBoundingClientRect().bottom));
}

// Filters over the metrics table: a menu per column named in `names`, listing its values.
function filterable(table, names) {
  const headers = Array.from(table.tHead.rows[0].cells).map((th) => th.textContent.trim());
  const columns = names.map((name) => headers.indexOf(name)).filter((i) => i >= 0);
  const rows = Array.from(table.tBodies[0].rows);
  const bar = document.createElement("div");
  bar.id = "filters";
  const menus = columns.map((column) => {
    const values = [...new Set(rows.map((r) => r.cells[column].textContent.trim()))].sort();
    const label = document.createElement("label");
    label.textContent = `${headers[column]} `;
    const menu = document.createElement("select");
    menu.dataset.column = String(column);
    menu.innerHTML = `<option value="">all</option>` +
      values.map((v) => `<option>${v.replace(/&/g, "&amp;").replace(/</g, "&lt;")}</option>`).join("");
    label.appendChild(menu);
    bar.appendChild(label);
    return menu;
  });
  const apply = () => {
    rows.forEach((row) => {
      const shown = menus.every((m) => !m.value || row.cells[Number(m.dataset.column)].textContent.trim() === m.value);
      row.style.display = shown ? "" : "none";
    });
  };
  menus.forEach((m) => m.addEventListener("change", apply));
  table.parentNode.insertBefore(bar, table);
}

document.addEventListener("DOMContentLoaded", () => {
  const table = document.getElementById("metrics");
  if (table) {
    sortable(table);
    filterable(table, ["scene", "method", "backend"]);
  }
  overview();
  viewer.thumbs = Array.from(document.querySelectorAll("figure.thumb"));
  viewer.thumbs.forEach((thumb, i) => thumb.addEventListener("click", () => open(i)));
  panAndZoom(document.getElementById("stage"));
  document.addEventListener("keydown", key);
  // Opening the report as index.html#view=N[&ev=S] shows job N in the viewer at exposure S.
  const match = /view=(\d+)/.exec(location.hash);
  const ev = /ev=(-?\d+)/.exec(location.hash);
  if (ev) viewer.exposure = Number(ev[1]);
  if (match && viewer.thumbs[Number(match[1])]) open(Number(match[1]));
});
