// ConeLOD web viewer — a picture of the page in headless Chromium (Debian's `chromium`), driven
// by playwright-core (npm, pinned in web/package.json).
//   node web/shoot.mjs URL OUT.png [--drag DX,DY] [URL2 OUT2.png [--drag DX,DY] ...] [--size WxH] [--timeout S]
// Loads each URL (the viewer's page with its parameters) in turn in one browser, waits until the
// page says it is done (window.conelod.state), writes the PNG of the page and prints
// window.conelod as one line of JSON on stdout.
// --drag DX,DY (after a page's pair): once that page is done, drag the mouse (left button) from
// the window's centre by DX, DY pixels (OrbitControls rotates the view) and wait until the new
// view is done; the picture and the figures are the new view's.
// Exit 0: all done; 2: a page reported an error (its message on stderr); 3: one timed out.
import { chromium } from 'playwright-core';

const args = process.argv.slice(2);
const usage = 'usage: node web/shoot.mjs URL OUT.png [URL2 OUT2.png ...] [--size WxH] [--timeout S]';
const pages = [];
const drags = {};  // page index -> [dx, dy]
let width = 800, height = 600, timeout = 120;
for (let i = 0; i < args.length; ++i) {
  if (args[i] === '--size' && i + 1 < args.length) {
    const m = /^(\d+)x(\d+)$/.exec(args[++i]);
    if (!m) { console.error('shoot.mjs: --size must be WxH, e.g. 800x600'); process.exit(1); }
    [width, height] = [Number(m[1]), Number(m[2])];
  } else if (args[i] === '--drag' && i + 1 < args.length && pages.length && pages.length % 2 === 0) {
    const drag = args[++i].split(',').map(Number);
    if (drag.length !== 2 || !drag.every(Number.isFinite)) { console.error('shoot.mjs: --drag must be DX,DY'); process.exit(1); }
    drags[pages.length - 2] = drag;
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
  // One page for all the URLs, loaded in turn (a new page costs seconds under SwiftShader).
  const page = await browser.newPage({ viewport: { width, height }, deviceScaleFactor: 1 });
  const logs = [];
  page.on('console', (m) => logs.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
  for (let p = 0; p < pages.length; p += 2) {
    const [url, out, drag] = [pages[p], pages[p + 1], drags[p]];
    logs.length = 0;
    await page.goto(url);
    let failed = 0;
    const finished = async (views) => {
      try {
        await page.waitForFunction((v) => window.conelod && (window.conelod.state === 'error' ||
          (window.conelod.state === 'done' && window.conelod.views >= v)), views, { timeout: timeout * 1000, polling: 50 });
        return true;
      } catch (e) {
        failed = 3;
        console.error(`shoot.mjs: ${url} did not finish within ${timeout} s`);
        return false;
      }
    };
    if ((await finished(1)) && drag) {
      const views = await page.evaluate(() => window.conelod.views);
      if (views !== undefined) {
        await page.mouse.move(width / 2, height / 2);
        await page.mouse.down();
        for (let k = 1; k <= 10; ++k) await page.mouse.move(width / 2 + (drag[0] * k) / 10, height / 2 + (drag[1] * k) / 10);
        await page.mouse.up();
        await finished(views + 1);
      }
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
  }
} finally {
  await browser.close();
}
process.exit(code);
