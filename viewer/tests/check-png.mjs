// Counts the pixels of a rendered picture by what they show: each loop colour (by hue, so shading does not
// matter), the surface (a light, unsaturated grey), the background. Prints one JSON object.
//   node check-png.mjs FILE.png
// The top-left corner (where the legend with its colour swatches sits) is left out of the counts.
import fs from 'node:fs';
import { PNG } from 'pngjs';

const file = process.argv[2];
if (!file) { console.error('usage: node check-png.mjs FILE.png'); process.exit(2); }
const png = PNG.sync.read(fs.readFileSync(file));
const { width, height, data } = png;
const LEGEND = { w: 300, h: 150 };
const counts = { 'handle generator': 0, 'handle choke': 0, 'tunnel generator': 0, 'tunnel choke': 0 };
let surface = 0, background = 0, other = 0, n = 0, sum = 0, sum2 = 0;
for (let y = 0; y < height; y++) {
  for (let x = 0; x < width; x++) {
    const o = 4 * (y * width + x);
    const r = data[o], g = data[o + 1], b = data[o + 2];
    const lum = 0.299 * r + 0.587 * g + 0.114 * b;
    n++; sum += lum; sum2 += lum * lum;
    if (x < LEGEND.w && y < LEGEND.h) continue;
    const max = Math.max(r, g, b), min = Math.min(r, g, b);
    const s = max ? (max - min) / max : 0, v = max / 255;
    let h = 0;
    if (max !== min) {
      if (max === r) h = (60 * (g - b)) / (max - min);
      else if (max === g) h = 120 + (60 * (b - r)) / (max - min);
      else h = 240 + (60 * (r - g)) / (max - min);
      if (h < 0) h += 360;
    }
    if (Math.abs(r - 244) + Math.abs(g - 245) + Math.abs(b - 247) <= 6) background++;
    else if (s > 0.5 && v > 0.25) {
      if (h < 12 || h >= 340) counts['handle generator']++;
      else if (h >= 22 && h < 45) counts['handle choke']++;
      else if (h >= 100 && h < 160) counts['tunnel choke']++;
      else if (h >= 205 && h < 240) counts['tunnel generator']++;
      else other++;
    } else if (s < 0.25 && v > 0.2) surface++;
    else other++;
  }
}
const mean = sum / n;
console.log(JSON.stringify({ file, width, height, counts, surface, background, other, variance: sum2 / n - mean * mean }));
