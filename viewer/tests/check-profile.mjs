// Opens OUTDIR/view.html of a molecule run in headless Chromium, clicks the table row of tunnel ID and checks
// that its radius profile is drawn: the plot names the loop, has as many points as loops.json's profile, and
// is laid out on the page (non-zero size); clicking a handle row clears it. Prints one JSON object.
//   node check-profile.mjs OUTDIR ID
import fs from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';
import { loadView, runPage } from './browser.mjs';

const [outdir, idArg] = process.argv.slice(2);
if (!outdir || idArg === undefined) { console.error('usage: node check-profile.mjs OUTDIR ID'); process.exit(2); }
const id = Number(idArg);
const report = JSON.parse(fs.readFileSync(path.join(outdir, 'loops.json'), 'utf8'));
const loop = (report.loops || []).find((l) => l.id === id);
const expected = loop && loop.channel && loop.channel.profile ? loop.channel.profile.s.length : -1;
const url = pathToFileURL(path.resolve(outdir, 'view.html')).href;
const failures = [];
const result = { url, id, expectedPoints: expected };
const check = (cond, msg) => { if (!cond) failures.push(msg); return cond; };

await runPage(result, failures, check, async ({ page }) => {
  await loadView(page, url);
  check(await page.locator('[data-testid=profile-panel]').count() === 1, 'no profile panel on a molecule page');
  check(await page.locator('[data-testid=profile-plot]').count() === 0, 'a profile is drawn before any selection');
  await page.locator(`[data-testid=loop-row][data-loop-id="${id}"]`).click();
  const plot = page.locator('[data-testid=profile-plot]');
  result.plots = await plot.count();
  if (check(result.plots === 1, `no profile plot after clicking tunnel ${id}`)) {
    result.plotLoop = Number(await plot.getAttribute('data-loop-id'));
    result.plotPoints = Number(await plot.getAttribute('data-points'));
    const box = await plot.boundingBox();
    result.box = box;
    const line = await page.locator('[data-testid=profile-line]').getAttribute('points');
    result.linePoints = line ? line.trim().split(/\s+/).length : 0;
    check(result.plotLoop === id, `the plot shows loop ${result.plotLoop}`);
    check(result.plotPoints === expected && result.linePoints === expected, `plot has ${result.plotPoints} / ${result.linePoints} points, loops.json ${expected}`);
    check(box && box.width > 100 && box.height > 50, 'the plot has no size on the page');
    check(await page.evaluate(() => window.chokeloopsView.profileLoop) === id, 'chokeloopsView.profileLoop');
  }
  const handle = (report.loops || []).find((l) => l.side === 'handle');
  if (handle) {
    await page.evaluate((h) => window.chokeloopsView.select(h), handle.id);
    check(await plot.count() === 0, 'selecting a handle kept the profile');
  }
});
