// Loads web/dist/medspring.mjs under node. Emscripten 3.1.6's ES module expects the CommonJS globals
// __dirname and require under node (the browser needs nothing).
import { fileURLToPath } from 'node:url';
import { createRequire } from 'node:module';
import path from 'node:path';

export const webDir = path.join(path.dirname(fileURLToPath(import.meta.url)), '..');

export async function loadMedSpring() {
  globalThis.__dirname = path.join(webDir, 'dist');
  globalThis.require = createRequire(import.meta.url);
  const { default: createMedSpring } = await import(path.join(webDir, 'dist', 'medspring.mjs'));
  return createMedSpring();
}
