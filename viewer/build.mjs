// Bundles src/main.js into one minified classic (IIFE) script: the report page is opened
// from file://, where ES modules and fetch() do not work. CSS is imported as text and
// injected at runtime, so the bundle is the only file the page needs.
//   node build.mjs [--outfile PATH] [--sourcemap] [--no-minify]
import * as esbuild from 'esbuild';
import { statSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const args = process.argv.slice(2);
let outfile = join(here, 'dist', 'snh-report.js');
const i = args.indexOf('--outfile');
if (i >= 0) {
  if (!args[i + 1]) {
    console.error('build.mjs: --outfile needs a path');
    process.exit(2);
  }
  outfile = args[i + 1];
}

try {
  const result = await esbuild.build({
    entryPoints: [join(here, 'src', 'main.js')],
    outfile,
    bundle: true,
    format: 'iife',
    target: 'es2020',
    minify: !args.includes('--no-minify'),
    sourcemap: args.includes('--sourcemap'),
    treeShaking: true,
    loader: { '.css': 'text' },
    legalComments: 'eof', // three.js and uPlot are MIT: their notices stay in the bundle
    banner: { js: '/*! snh report viewer. Bundles three.js (MIT License, Copyright 2010-2026 Three.js Authors) and uPlot (MIT License, Copyright (c) 2025 Leon Sorokin). */' },
    logLevel: 'warning',
  });
  if (result.errors.length) throw new Error(`${result.errors.length} error(s)`);
  const kib = (statSync(outfile).size / 1024).toFixed(1);
  console.log(`build.mjs: wrote ${outfile} (${kib} KiB)`);
} catch (e) {
  // esbuild has already printed the details of each error
  console.error(`build.mjs: the bundle was not built: ${e.message.split('\n')[0]}`);
  process.exit(1);
}
