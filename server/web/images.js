// Images as exact pixels: PNG through the browser's decoder with no colour conversion, PPM
// (P6 and P3, which browsers cannot show) by hand, both to ImageData for canvases.

function isSpace(b) {
  return b === 0x20 || b === 0x09 || b === 0x0a || b === 0x0d || b === 0x0b || b === 0x0c;
}

export function decodePpm(bytes) {
  let pos = 0;
  const word = () => {
    for (;;) {
      while (pos < bytes.length && isSpace(bytes[pos])) pos++;
      if (bytes[pos] !== 0x23) break;  // '#' comment to the end of the line
      while (pos < bytes.length && bytes[pos] !== 0x0a) pos++;
    }
    const start = pos;
    while (pos < bytes.length && !isSpace(bytes[pos]) && bytes[pos] !== 0x23) pos++;
    return new TextDecoder().decode(bytes.subarray(start, pos));
  };
  const magic = word();
  const width = Number(word());
  const height = Number(word());
  const max = Number(word());
  if ((magic !== 'P6' && magic !== 'P3') || !(width > 0) || !(height > 0) || !(max > 0 && max < 65536))
    throw new Error('not a PPM image this page can read (P6 or P3)');
  const out = new ImageData(width, height);
  const scale = (v) => Math.round((v * 255) / max);
  const wide = max > 255;
  if (magic === 'P6') pos++;  // the one whitespace byte before the samples
  for (let i = 0; i < width * height; i++) {
    for (let c = 0; c < 3; c++) {
      let v;
      if (magic === 'P3') {
        v = Number(word());
      } else if (wide) {
        v = (bytes[pos] << 8) | bytes[pos + 1];
        pos += 2;
      } else {
        v = bytes[pos++];
      }
      if (!(v >= 0) || v > max) throw new Error('the PPM image is cut short or has bad samples');
      out.data[i * 4 + c] = max === 255 ? v : scale(v);
    }
    out.data[i * 4 + 3] = 255;
  }
  return out;
}

export async function decodeImage(blob) {
  const head = new Uint8Array(await blob.slice(0, 2).arrayBuffer());
  if (head[0] === 0x50 && (head[1] === 0x36 || head[1] === 0x33))
    return decodePpm(new Uint8Array(await blob.arrayBuffer()));
  let bitmap;
  try {
    bitmap = await createImageBitmap(blob, {
      colorSpaceConversion: 'none',
      premultiplyAlpha: 'none',
    });
  } catch {
    throw new Error('not an image this page can read (PNG or PPM)');
  }
  const canvas = document.createElement('canvas');
  canvas.width = bitmap.width;
  canvas.height = bitmap.height;
  const ctx = canvas.getContext('2d', { willReadFrequently: true });
  ctx.drawImage(bitmap, 0, 0);
  bitmap.close();
  return ctx.getImageData(0, 0, canvas.width, canvas.height);
}

export function paint(canvas, imageData) {
  canvas.width = imageData.width;
  canvas.height = imageData.height;
  canvas.getContext('2d').putImageData(imageData, 0, 0);
}
