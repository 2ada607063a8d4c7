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
  stage.querySelectorAll("img").forEach((img) => {
    img.style.transform = transform;
    const colour = img.dataset.kind === "colour";
    img.style.filter = colour ? `brightness(${Math.pow(2, viewer.exposure)})` : "none";
  });
  const thumb = viewer.thumbs[viewer.index];
  const side = viewer.mode === "flip" ? (viewer.showReference ? "reference" : "method") : "reference | method";
  document.getElementById("bar").innerHTML =
    `<b>${thumb.dataset.title}</b> &nbsp; ${viewer.layer} · ${viewer.mode} (${side}) · exposure ${viewer.exposure >= 0 ? "+" : ""}${viewer.exposure} EV · zoom ${viewer.zoom.toFixed(2)}×<br>` +
    "<kbd>1</kbd> image <kbd>2</kbd> FLIP <kbd>3</kbd> T2 error <kbd>4</kbd> missed objects · " +
    "<kbd>s</kbd> slider <kbd>f</kbd> flip A/B · <kbd>e</kbd>/<kbd>E</kbd> exposure · " +
    "wheel zoom, shift+drag pan, <kbd>0</kbd> reset · <kbd>←</kbd>/<kbd>→</kbd> previous/next · <kbd>Esc</kbd> close";
}

function image(src, kind, slot) {
  const img = document.createElement("img");
  img.src = src;
  img.dataset.kind = kind;
  img.draggable = false;
  img.width = 512;
  if (slot) img.slot = slot;
  return img;
}

function render() {
  const thumb = viewer.thumbs[viewer.index];
  const stage = document.getElementById("stage");
  stage.textContent = "";
  const methodKind = viewer.layer === "image" || viewer.layer === "miss" ? "colour" : "map";
  const method = image(layerSource(thumb), methodKind);
  const reference = image(thumb.dataset.reference, "colour");
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

document.addEventListener("DOMContentLoaded", () => {
  const table = document.getElementById("metrics");
  if (table) sortable(table);
  viewer.thumbs = Array.from(document.querySelectorAll("figure.thumb"));
  viewer.thumbs.forEach((thumb, i) => thumb.addEventListener("click", () => open(i)));
  panAndZoom(document.getElementById("stage"));
  document.addEventListener("keydown", key);
  // Opening the report as index.html#view=N shows job N in the viewer (used by tests).
  const match = /view=(\d+)/.exec(location.hash);
  if (match && viewer.thumbs[Number(match[1])]) open(Number(match[1]));
});
