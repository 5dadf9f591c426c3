// The headless Chromium the page checks share (playwright-core driving Debian's chromium; CHOKELOOPS_CHROMIUM
// overrides the binary): a 1400x900 context that records every request leaving file:/data: URLs, and a page
// that records its console errors and uncaught exceptions.
import { chromium } from 'playwright-core';

export async function openBrowser() {
  const browser = await chromium.launch({
    executablePath: process.env.CHOKELOOPS_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--disable-gpu', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync', '--disable-quic', '--disable-dev-shm-usage', '--enable-unsafe-swiftshader'],
  });
  const context = await browser.newContext({ viewport: { width: 1400, height: 900 }, deviceScaleFactor: 1 });
  const requests = [];
  context.on('request', (r) => { if (!r.url().startsWith('file:') && !r.url().startsWith('data:')) requests.push(r.url()); });
  const page = await context.newPage();
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(`console: ${m.text()}`); });
  page.on('pageerror', (e) => errors.push(`pageerror: ${e.message}`));
  return { browser, context, page, requests, errors };
}

// Loads the page and waits until the viewer is ready (or has reported an error).
export async function loadView(page, url) {
  await page.goto(url, { waitUntil: 'load', timeout: 120000 });
  await page.waitForFunction(() => window.chokeloopsView && (window.chokeloopsView.ready || window.chokeloopsView.errors.length), null, { timeout: 120000 });
}

// Runs `body(session)` on a fresh browser, then checks that the page logged no errors and requested nothing
// from the network, prints `result` (with its failures) as JSON and exits 1 when a check failed.
export async function runPage(result, failures, check, body) {
  const session = await openBrowser();
  try {
    await body(session);
    result.errors = session.errors;
    result.externalRequests = session.requests;
    check(session.errors.length === 0, `console errors: ${session.errors.join(' | ')}`);
    check(session.requests.length === 0, `the page requested: ${session.requests.join(', ')}`);
  } catch (e) {
    failures.push(`exception: ${e && e.stack || e}`);
  } finally {
    await session.browser.close();
  }
  result.failures = failures;
  result.ok = failures.length === 0;
  console.log(JSON.stringify(result, null, 1));
  process.exit(result.ok ? 0 : 1);
}
