// What every engine page does with the pixels it read back (engines/README.md).

// `rows`, RGBA floats as WebGL reads them (rows from the bottom), as refract takes a frame:
// rows from the top, the float bytes in base64 (render.mjs decodes them into `<variant>.f32`).
export function topDownBase64(rows, width, height) {
  const pixels = new Float32Array(width * height * 4);
  for (let y = 0; y < height; y++) {
    pixels.set(rows.subarray((height - 1 - y) * width * 4, (height - y) * width * 4), y * width * 4);
  }
  const bytes = new Uint8Array(pixels.buffer);
  let text = '';
  const chunk = 0x8000;
  for (let i = 0; i < bytes.length; i += chunk) {
    text += String.fromCharCode.apply(null, bytes.subarray(i, i + chunk));
  }
  return btoa(text);
}
