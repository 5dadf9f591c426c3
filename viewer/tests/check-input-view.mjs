// Opens OUTDIR/view.html of a mesh input in headless Chromium and checks the input-mesh view: the page
// starts on the marching surface, its "show the input mesh" button switches to input_mesh.ply with the loops
// of input_loops.json (every loop in the table, a carried loop clickable in 3D and drawn in its colour),
// and back. Prints one JSON object {ok, failures, ...}; exits 1 when a check fails.
//   node check-input-view.mjs OUTDIR
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { loadView, runPage } from './browser.mjs';
import { PNG } from 'pngjs';

const outdir = process.argv[2];
if (!outdir) { console.error('usage: node check-input-view.mjs OUTDIR'); process.exit(2); }
const marching = JSON.parse(fs.readFileSync(path.join(outdir, 'loops.json'), 'utf8')).loops || [];
const input = JSON.parse(fs.readFileSync(path.join(outdir, 'input_loops.json'), 'utf8')).loops || [];
const header = fs.readFileSync(path.join(outdir, 'input_mesh.ply')).subarray(0, 4096).toString('latin1');
const inputFaces = Number((/element face (\d+)/.exec(header) || [])[1]);
const url = pathToFileURL(path.resolve(outdir, 'view.html')).href;

const failures = [];
const result = { url, marchingLoops: marching.length, inputLoops: input.length, inputFaces };
const check = (cond, msg) => { if (!cond) failures.push(msg); return cond; };

const pageState = (page) => page.evaluate(() => {
  const s = window.chokeloopsView;
  return { ready: s.ready, surfaceKind: s.surfaceKind, hasInputMesh: s.hasInputMesh, loopCount: s.loopCount,
    sourceFaces: s.sourceFaces, displayFaces: s.displayFaces, categories: s.categories, errors: s.errors };
});

await runPage(result, failures, check, async ({ page }) => {
  await loadView(page, url);
  const before = await pageState(page);
  result.before = before;
  check(before.hasInputMesh, 'the page of a mesh input holds no input mesh');
  check(before.surfaceKind === 'marching', `the page opens on ${before.surfaceKind}, not the marching surface`);
  check(before.loopCount === marching.length, `marching view shows ${before.loopCount} loops, loops.json has ${marching.length}`);
  check(await page.getAttribute('[data-testid=surface-kind]', 'data-kind') === 'marching', 'the panel does not say which surface is shown');

  await Promise.all([page.waitForEvent('load'), page.click('[data-testid=surface-toggle]')]);
  await page.waitForFunction(() => window.chokeloopsView && (window.chokeloopsView.ready || window.chokeloopsView.errors.length));
  const after = await pageState(page);
  result.after = after;
  check(after.surfaceKind === 'input', `after the toggle the page shows ${after.surfaceKind}`);
  check(/(^|[#&])input\b/.test(await page.evaluate(() => location.hash)), 'the toggle did not set #input');
  check(after.sourceFaces === inputFaces, `input view has ${after.sourceFaces} source faces, input_mesh.ply ${inputFaces}`);
  check(after.loopCount === input.length, `input view shows ${after.loopCount} loops, input_loops.json has ${input.length}`);
  check(await page.locator('[data-testid=loop-row]').count() === input.length, 'the table does not list every input loop');
  check(await page.getAttribute('[data-testid=surface-kind]', 'data-kind') === 'input', 'the panel does not say the input mesh is shown');

  // A carried loop is drawn where input_loops.json puts it: clicking it in 3D selects it.
  const target = input.filter((l) => l.found && l.points.length >= 3).sort((a, b) => b.length - a.length)[0];
  check(!!target, 'no carried loop to click');
  if (target) {
    await page.click('[data-testid=reset-view]');
    await page.waitForTimeout(200);
    const at = await page.evaluate(([id, k]) => window.chokeloopsView.screenPosition(id, k), [target.id, Math.floor(target.points.length / 4)]);
    await page.mouse.click(at.x, at.y);
    const sel = await page.evaluate(() => window.chokeloopsView.selectedLoop);
    result.clicked3d = { loop: target.id, at, selected: sel };
    check(sel === target.id, `clicking input loop ${target.id} in 3D at ${JSON.stringify(at)} selected ${sel}`);
    await page.keyboard.press('Escape');
  }
  const shot = PNG.sync.read(await page.locator('[data-testid=viewport]').screenshot());
  let coloured = 0;  // pixels of a loop colour: strongly red or blue
  for (let i = 0; i < shot.width * shot.height; i++) {
    const r = shot.data[4 * i], g = shot.data[4 * i + 1], b = shot.data[4 * i + 2];
    if ((r > 180 && g < 90 && b < 90) || (b > 180 && r < 90 && g < 150)) coloured++;
  }
  result.loopPixels = coloured;
  check(coloured > 200, `the input view shows ${coloured} loop-coloured pixels`);

  await Promise.all([page.waitForEvent('load'), page.click('[data-testid=surface-toggle]')]);
  await page.waitForFunction(() => window.chokeloopsView && (window.chokeloopsView.ready || window.chokeloopsView.errors.length));
  const back = await pageState(page);
  check(back.surfaceKind === 'marching' && back.loopCount === marching.length, `the toggle back shows ${back.surfaceKind} with ${back.loopCount} loops`);
});
