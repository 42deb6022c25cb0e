// Checks the layout of self-contained HTML pages in headless Chromium: no clipped label.
//
//   node tests/browser/layout.mjs PAGE.html [PAGE.html ...]
//
// Opens each page (file://, a fresh profile, a 1280 x 900 viewport; the pages load
// nothing from the network) in Debian's Chromium through playwright-core
// (WAGASHI_CHROMIUM overrides /usr/bin/chromium) and lists, per page:
// - every SVG <text> whose bounding box leaves its <svg>'s box (clipped);
// - every pair of <text> boxes in one <svg> that overlap (by more than 0.5 px both ways);
// - every table cell, and every table, whose scrollWidth exceeds its clientWidth
//   (content overflowing), and every table wider than its container.
// Prints one JSON object on stdout: {"pages": [{"file", "svgs", "texts", "cells", "defects": [...]}]}.
// Exit status 0 when it ran (defects or not; the caller judges), 1 when a page fails, 2 on usage.
import { mkdtemp, rm } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { chromium } from 'playwright-core';

const files = process.argv.slice(2).map((p) => resolve(p));
if (files.length === 0 || files.some((f) => f.startsWith('-'))) {
  console.error('usage: node layout.mjs PAGE.html [PAGE.html ...]');
  process.exit(2);
}

const watchdog = setTimeout(() => {
  console.error('layout.mjs: timed out after 120 s');
  process.exit(1);
}, 120_000);

// Runs inside the page.
function check() {
  const tol = 0.5;
  const defects = [];
  const box = (r) => ({ x0: r.left, y0: r.top, x1: r.right, y1: r.bottom });
  const fmt = (b) => `[${b.x0.toFixed(1)}, ${b.y0.toFixed(1)}; ${b.x1.toFixed(1)}, ${b.y1.toFixed(1)}]`;
  const where = (el) => {
    const parts = [];
    for (let e = el; e && e !== document.body; e = e.parentElement) {
      const siblings = e.parentElement ? [...e.parentElement.children].filter((c) => c.tagName === e.tagName) : [];
      parts.unshift(siblings.length > 1 ? `${e.tagName.toLowerCase()}[${siblings.indexOf(e) + 1}]` : e.tagName.toLowerCase());
    }
    return parts.join('>');
  };
  const svgs = [...document.querySelectorAll('svg')];
  let texts = 0;
  for (const svg of svgs) {
    const frame = box(svg.getBoundingClientRect());
    const labels = [...svg.querySelectorAll('text')].map((t) => ({ t, b: box(t.getBoundingClientRect()) }));
    texts += labels.length;
    for (const { t, b } of labels) {
      if (b.x0 < frame.x0 - tol || b.y0 < frame.y0 - tol || b.x1 > frame.x1 + tol || b.y1 > frame.y1 + tol) {
        defects.push(`clipped: ${where(svg)}: "${t.textContent}" at ${fmt(b)} outside the svg's ${fmt(frame)}`);
      }
    }
    for (let i = 0; i < labels.length; i++) {
      for (let j = i + 1; j < labels.length; j++) {
        const [a, b] = [labels[i].b, labels[j].b];
        const dx = Math.min(a.x1, b.x1) - Math.max(a.x0, b.x0);
        const dy = Math.min(a.y1, b.y1) - Math.max(a.y0, b.y0);
        if (dx > tol && dy > tol) {
          defects.push(
            `overlap: ${where(svg)}: "${labels[i].t.textContent}" ${fmt(a)} and "${labels[j].t.textContent}" ${fmt(b)}`,
          );
        }
      }
    }
  }
  let cells = 0;
  for (const table of document.querySelectorAll('table')) {
    for (const el of [table, ...table.querySelectorAll('td, th')]) {
      cells += 1;
      if (el.scrollWidth > el.clientWidth) {
        defects.push(`overflow: ${where(el)}: scrollWidth ${el.scrollWidth} > clientWidth ${el.clientWidth}: "${el.textContent.slice(0, 60)}"`);
      }
    }
    const parent = table.parentElement;
    if (table.getBoundingClientRect().right > parent.getBoundingClientRect().right + tol) {
      defects.push(`overflow: ${where(table)} is wider than its container`);
    }
  }
  return { svgs: svgs.length, texts, cells, defects };
}

const profile = await mkdtemp(join(tmpdir(), 'wagashi-chromium-'));
let context;
let status = 0;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.WAGASHI_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    viewport: { width: 1280, height: 900 },
    deviceScaleFactor: 1,
    args: [
      '--headless',
      '--no-sandbox',
      '--disable-gpu',
      '--no-first-run',
      '--disable-background-networking',
      '--disable-component-update',
      '--disable-sync',
    ],
  });
  const tab = context.pages()[0] ?? (await context.newPage());
  const pages = [];
  for (const file of files) {
    await tab.goto(pathToFileURL(file).href);
    await tab.evaluate(() => document.fonts.ready);
    pages.push({ file, ...(await tab.evaluate(check)) });
  }
  console.log(JSON.stringify({ pages }, null, 1));
} catch (error) {
  console.error(`layout.mjs: ${error.stack ?? error}`);
  status = 1;
} finally {
  await context?.close().catch(() => {});
  await rm(profile, { recursive: true, force: true });
  clearTimeout(watchdog);
}
process.exit(status);
