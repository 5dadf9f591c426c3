// Opens OUTDIR/view.html in headless Chromium (playwright-core driving Debian's chromium) and checks it the
// way a person would use it. Prints one JSON object {ok, failures, ...}; exits 1 when a check fails.
//   node check-view.mjs OUTDIR [--expect-decimated] [--screenshot FILE.png]
// CHOKELOOPS_CHROMIUM overrides the browser (default /usr/bin/chromium).
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { loadView, runPage } from './browser.mjs';
import { PNG } from 'pngjs';

const args = process.argv.slice(2);
const outdir = args.find((a) => !a.startsWith('--'));
if (!outdir) { console.error('usage: node check-view.mjs OUTDIR [--expect-decimated] [--screenshot FILE.png]'); process.exit(2); }
const expectDecimated = args.includes('--expect-decimated');
const shotArg = args.indexOf('--screenshot');
const shotFile = shotArg >= 0 ? args[shotArg + 1] : null;
const report = JSON.parse(fs.readFileSync(path.join(outdir, 'loops.json'), 'utf8'));
const loops = report.loops || [];
const url = pathToFileURL(path.resolve(outdir, 'view.html')).href;

const failures = [];
const result = { url, expectedLoops: loops.length };
const check = (cond, msg) => { if (!cond) failures.push(msg); return cond; };

function pixelStats(buf) {
  const { width, height, data } = PNG.sync.read(buf);
  let n = 0, s = 0, s2 = 0;
  const colours = new Set();
  for (let i = 0; i < width * height; i++) {
    const l = 0.299 * data[4 * i] + 0.587 * data[4 * i + 1] + 0.114 * data[4 * i + 2];
    n++; s += l; s2 += l * l;
    if (colours.size < 5000) colours.add((data[4 * i] >> 3) << 10 | (data[4 * i + 1] >> 3) << 5 | (data[4 * i + 2] >> 3));
  }
  const m = s / n;
  return { width, height, variance: Math.round(s2 / n - m * m), colours: colours.size };
}

await runPage(result, failures, check, async ({ context, page, errors }) => {
  const t0 = Date.now();
  await loadView(page, url);
  result.loadMs = Date.now() - t0;
  const st = await page.evaluate(() => {
    const s = window.chokeloopsView;
    return { ready: s.ready, webgl: s.webgl, loopCount: s.loopCount, errors: s.errors, decimated: s.decimated,
      displayFaces: s.displayFaces, sourceFaces: s.sourceFaces, categories: s.categories };
  });
  Object.assign(result, { state: st });
  check(st.ready, 'page did not become ready');
  check(st.webgl, 'WebGL unavailable in the page');
  check(st.errors.length === 0, `page reported errors: ${st.errors.join(' | ')}`);

  // The number of loops the page shows.
  const shown = Number(await page.getAttribute('[data-testid=loop-count]', 'data-count'));
  const shownText = (await page.textContent('[data-testid=loop-count]')).trim();
  const rows = await page.locator('[data-testid=loop-row]').count();
  const points = await page.locator('[data-testid=diagram-point]').count();
  Object.assign(result, { shownLoops: shown, shownText, rows, diagramPoints: points });
  check(shown === loops.length && shownText === String(loops.length), `page shows ${shownText} loops, loops.json has ${loops.length}`);
  check(st.loopCount === loops.length, `chokeloopsView.loopCount ${st.loopCount} != ${loops.length}`);
  check(rows === loops.length, `table has ${rows} rows, loops.json has ${loops.length}`);
  check(points === loops.length, `diagrams have ${points} loop points, loops.json has ${loops.length}`);
  for (const side of ['handle', 'tunnel']) {
    check(await page.locator(`[data-testid=diagram-${side}]`).count() === 1, `no ${side} diagram`);
    if (report.parameters && (Number.isFinite(report.parameters.d_max_abs) || Number.isFinite(report.parameters[`d_max_abs_${side}`])))
      check(await page.locator(`[data-testid=threshold-dmax-${side}]`).count() === 1, `no d_max line in the ${side} diagram`);
    if (report.parameters && Number.isFinite(report.parameters[`min_persistence_abs_${side}`]))
      check(await page.locator(`[data-testid=threshold-pmin-${side}]`).count() === 1, `no δ_min line in the ${side} diagram`);
  }
  const legend = await page.locator('[data-testid=legend] label').count();
  check(legend === 4, `legend has ${legend} entries, expected 4`);

  if (loops.length) {
    // Sorting: by persistence, descending after two clicks.
    await page.click('[data-testid=sort-persistence]');
    let order = await page.evaluate(() => window.chokeloopsView.rowOrder);
    const pers = new Map(loops.map((l) => [l.id, l.persistence]));
    const asc = order.every((id, i) => i === 0 || pers.get(order[i - 1]) <= pers.get(id));
    await page.click('[data-testid=sort-persistence]');
    order = await page.evaluate(() => window.chokeloopsView.rowOrder);
    const desc = order.every((id, i) => i === 0 || pers.get(order[i - 1]) >= pers.get(id));
    const domOrder = await page.locator('[data-testid=loop-row]').evaluateAll((rs) => rs.map((r) => Number(r.dataset.loopId)));
    check(asc && desc && JSON.stringify(domOrder) === JSON.stringify(order), 'sorting by persistence does not order the rows');

    // Clicking a row selects its loop.
    const rowIndex = Math.min(1, loops.length - 1);
    const row = page.locator('[data-testid=loop-row]').nth(rowIndex);
    const rowId = Number(await row.getAttribute('data-loop-id'));
    await row.click();
    await page.waitForTimeout(600);  // the camera flies to the loop
    const sel = await page.evaluate(() => window.chokeloopsView.selectedLoop);
    const selRows = await page.locator('[data-testid=loop-row][aria-selected=true]').evaluateAll((rs) => rs.map((r) => Number(r.dataset.loopId)));
    const selPts = await page.locator('[data-testid=diagram-point].selected').evaluateAll((ps) => ps.map((p) => Number(p.dataset.loopId)));
    Object.assign(result, { clickedRow: rowId, selectedAfterRowClick: sel, selectedRows: selRows });
    check(sel === rowId, `clicking the row of loop ${rowId} selected ${sel}`);
    check(selRows.length === 1 && selRows[0] === rowId, `highlighted rows after the click: ${JSON.stringify(selRows)}`);
    check(selPts.length >= 1 && selPts.every((id) => id === rowId), `highlighted diagram points: ${JSON.stringify(selPts)}`);
    if (shotFile) await page.locator('[data-testid=viewport]').screenshot({ path: shotFile.replace(/\.png$/, '-selected.png') });

    // Clicking a point in the diagram selects its loop (a generator: drawn on top).
    // Points can overlap: use one that is on top at its centre.
    const onTop = await page.locator('[data-testid=diagram-point]').evaluateAll((ps) => ps.filter((p) => {
      const r = p.getBoundingClientRect();
      p.scrollIntoView({ block: 'center' });
      const r2 = p.getBoundingClientRect();
      return document.elementFromPoint(r2.left + r2.width / 2, r2.top + r2.height / 2) === p && r.width > 0;
    }).map((p) => Number(p.dataset.loopId)));
    const other = loops.find((l) => l.id !== rowId && onTop.includes(l.id));
    if (other) {
      await page.locator(`[data-testid=diagram-point][data-loop-id="${other.id}"]`).click();
      const sel2 = await page.evaluate(() => window.chokeloopsView.selectedLoop);
      result.selectedAfterPointClick = sel2;
      check(sel2 === other.id, `clicking the diagram point of loop ${other.id} selected ${sel2}`);
    }
  }

  // Clicking a loop in the 3D view selects it (the longest tunnel loop, a quarter of the way round: away
  // from the handle loops in the default view), and Escape clears the selection.
  const target = loops.filter((l) => l.side === 'tunnel').sort((a, b) => b.length - a.length)[0];
  if (target) {
    await page.click('[data-testid=reset-view]');
    await page.waitForTimeout(200);
    const at = await page.evaluate((id) => window.chokeloopsView.screenPosition(id, Math.floor(
      JSON.parse(document.getElementById('chokeloops-data').textContent).report.loops.find((l) => l.id === id).points.length / 4)), target.id);
    await page.mouse.click(at.x, at.y);
    const sel3 = await page.evaluate(() => window.chokeloopsView.selectedLoop);
    result.clicked3d = { loop: target.id, at, selected: sel3 };
    check(sel3 === target.id, `clicking loop ${target.id} in the 3D view at ${JSON.stringify(at)} selected ${sel3}`);
    await page.keyboard.press('Escape');
    const sel4 = await page.evaluate(() => window.chokeloopsView.selectedLoop);
    check(sel4 === null, `Escape left loop ${sel4} selected`);
  }

  // Surface opacity slider.
  await page.locator('[data-testid=opacity-slider]').fill('0.5');
  const op = await page.evaluate(() => window.chokeloopsView.surfaceOpacity);
  check(Math.abs(op - 0.5) < 1e-9, `opacity slider set 0.5, surface opacity is ${op}`);
  await page.locator('[data-testid=opacity-slider]').fill('1');
  await page.click('[data-testid=reset-view]');
  await page.waitForTimeout(300);

  // Decimation note.
  const note = await page.locator('[data-testid=decimation-note]').count();
  result.decimationNote = note ? (await page.textContent('[data-testid=decimation-note]')) : null;
  if (expectDecimated) {
    check(note === 1 && st.decimated, 'no decimation note for a surface over the face budget');
    check(st.displayFaces <= 300000 && st.displayFaces > 1000, `displayed ${st.displayFaces} faces`);
  } else {
    check(note === 0 && !st.decimated, 'a small surface was decimated');
  }

  // Frame time while orbiting (software WebGL here: a GPU is much faster).
  result.frameMs = Math.round(await page.evaluate(() => window.chokeloopsView.timeFrames(10)));
  await page.click('[data-testid=reset-view]');
  await page.waitForTimeout(200);

  // The 3D view is not blank.
  const shot = await page.locator('[data-testid=viewport]').screenshot(shotFile ? { path: shotFile } : {});
  result.viewport = pixelStats(shot);
  check(result.viewport.variance > 40 && result.viewport.colours > 20, `the 3D view looks blank: ${JSON.stringify(result.viewport)}`);

  // Render mode (what `chokeloops render` photographs).
  const rpage = await context.newPage();
  rpage.on('console', (m) => { if (m.type() === 'error') errors.push(`render console: ${m.text()}`); });
  rpage.on('pageerror', (e) => errors.push(`render pageerror: ${e.message}`));
  await rpage.goto(url + '#render', { waitUntil: 'load', timeout: 120000 });
  const rst = await rpage.evaluate(() => ({ rendered: window.chokeloopsView.rendered, panel: getComputedStyle(document.getElementById('panel')).display }));
  result.renderMode = rst;
  check(rst.rendered && rst.panel === 'none', `render mode: ${JSON.stringify(rst)}`);

  // view.html#loop=ID opens with that loop selected.
  if (loops.length) {
    const id = loops[loops.length - 1].id;
    const lpage = await context.newPage();
    lpage.on('pageerror', (e) => errors.push(`#loop pageerror: ${e.message}`));
    await lpage.goto(`${url}#loop=${id}`, { waitUntil: 'load', timeout: 120000 });
    const lsel = await lpage.evaluate(() => window.chokeloopsView.selectedLoop);
    check(lsel === id, `#loop=${id} selected ${lsel}`);
  }

});
