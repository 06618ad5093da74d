// ConeLOD web viewer — a picture of the page in headless Chromium (Debian's `chromium`), driven
// by playwright-core (npm, pinned in web/package.json).
//   node web/shoot.mjs URL OUT.png [URL2 OUT2.png ...] [--size WxH] [--timeout S]
// Loads each URL (the viewer's page with its parameters) in turn in one browser, waits until the
// page says it is done (window.conelod.state), writes the PNG of the page and prints
// window.conelod as one line of JSON on stdout.
// Exit 0: all done; 2: a page reported an error (its message on stderr); 3: one timed out.
import { chromium } from 'playwright-core';

const args = process.argv.slice(2);
const usage = 'usage: node web/shoot.mjs URL OUT.png [URL2 OUT2.png ...] [--size WxH] [--timeout S]';
const pages = [];
let width = 800, height = 600, timeout = 120;
for (let i = 0; i < args.length; ++i) {
  if (args[i] === '--size' && i + 1 < args.length) {
    const m = /^(\d+)x(\d+)$/.exec(args[++i]);
    if (!m) { console.error('shoot.mjs: --size must be WxH, e.g. 800x600'); process.exit(1); }
    [width, height] = [Number(m[1]), Number(m[2])];
  } else if (args[i] === '--timeout' && i + 1 < args.length) {
    timeout = Number(args[++i]);
  } else {
    pages.push(args[i]);
  }
}
if (!pages.length || pages.length % 2) { console.error(usage); process.exit(1); }

const executablePath = process.env.CHROMIUM || '/usr/bin/chromium';
// WebGL without a GPU: SwiftShader through ANGLE (Chromium's software renderer).
const browser = await chromium.launch({
  executablePath,
  headless: true,
  args: ['--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--no-sandbox'],
});
let code = 0;
try {
  for (let p = 0; p < pages.length; p += 2) {
    const [url, out] = [pages[p], pages[p + 1]];
    const page = await browser.newPage({ viewport: { width, height }, deviceScaleFactor: 1 });
    const logs = [];
    page.on('console', (m) => logs.push(`${m.type()}: ${m.text()}`));
    page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
    await page.goto(url);
    let failed = 0;
    try {
      await page.waitForFunction(() => window.conelod && (window.conelod.state === 'done' || window.conelod.state === 'error'),
        null, { timeout: timeout * 1000, polling: 50 });
    } catch (e) {
      failed = 3;
      console.error(`shoot.mjs: ${url} did not finish within ${timeout} s`);
    }
    const status = await page.evaluate(() => window.conelod || null);
    await page.screenshot({ path: out });
    if (status && status.state === 'error') {
      failed = 2;
      console.error('conelod: ' + status.error);
    }
    if (failed) for (const l of logs) console.error(l);
    console.log(JSON.stringify(status));
    code = code || failed;
    await page.close();
  }
} finally {
  await browser.close();
}
process.exit(code);
