// ConeLOD web viewer — the page: opens the .clod named by ?file= over HTTP Range requests, draws
// the coarsest cut (the roots) at once, then refines by screen-space error within a face budget
// (refine.js) while the view is still, and again from the roots (its reads cached) whenever the
// view changes. Orbit/zoom: three.js's OrbitControls. Keys: c cycles the colours (the file's
// attributes: its texture image (stored in the file, shown through a Blob URL) or vertex colours,
// with smooth shading by its normals when it has them; shaded grey, one per level, one per group
// of its level, one per node), a switches between the file's attributes and the level colours,
// h hides the text.
//
// Page parameters: file (URL of the .clod, relative to the page), budget (faces, default
// 500000), pixel (screen-space error in pixels, default 1), eye=X,Y,Z (model coordinates; default:
// in front, +Z, framing the box), color=vertex|none|level|group|node (default: vertex when the file
// has colours, normals or texture coordinates, else none), texture=0 (the file's attributes
// without its texture image), hud=0, cull=0 (no back-face culling), refine=0 (draw the roots
// only), fps=N (after refinement, time N frames).
// For scripts (web/shoot.mjs): window.conelod holds the state ('loading', 'refining', 'done',
// 'error'), the views refined so far, the eye and the figures; the title ends in "[done]" or
// "[error]".
import * as THREE from 'three';
import { OrbitControls } from './node_modules/three/examples/jsm/controls/OrbitControls.js';
import { ClodReader, decodeNormal, decodeTexCoords } from './clod.js';
import { Refiner, projectedError } from './refine.js';

const params = new URLSearchParams(location.search);
const FOV = 35;  // degrees, as conelod-viewer
const status = (window.conelod = { state: 'loading' });
const hud = document.getElementById('hud');
if (params.get('hud') === '0') hud.style.display = 'none';

function fail(e) {
  status.state = 'error';
  status.error = e && e.message ? e.message : String(e);
  document.getElementById('error').textContent = 'conelod: ' + status.error;
  document.title = 'ConeLOD web viewer [error]';
  console.error(e);
}

function numberParam(name, def) {
  const v = params.get(name);
  if (v === null) return def;
  const x = Number(v);
  if (!Number.isFinite(x) || x < 0) throw new Error(`page parameter ${name}=${v} is not a non-negative number`);
  return x;
}

// sRGB byte -> linear (three.js works in linear sRGB and encodes its output as sRGB).
const SRGB_TO_LINEAR = Float32Array.from({ length: 256 }, (_, i) => {
  const c = i / 255;
  return c < 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4;
});

const nextFrame = () => new Promise((r) => requestAnimationFrame(() => r()));

async function main() {
  const file = params.get('file');
  if (!file) throw new Error('no file: open this page as ?file=NAME.clod (conelod serve FILE.clod prints the URL)');
  const budget = numberParam('budget', 500000), pixelError = numberParam('pixel', 1);
  const t0 = performance.now();
  const reader = await ClodReader.open(new URL(file, location.href).href);
  const info = reader.info;
  status.fileBytes = info.fileBytes;
  status.inputFaces = info.inputFaces;
  status.levels = info.levels;

  const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(window.innerWidth, window.innerHeight);
  renderer.setClearColor(0x262a33);
  document.body.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.add(new THREE.AmbientLight(0xffffff, 0.35));
  const camera = new THREE.PerspectiveCamera(FOV, window.innerWidth / window.innerHeight, 0.01, 100);
  const light = new THREE.DirectionalLight(0xffffff, 2.2);
  light.position.set(0.3, 0.4, 1);
  camera.add(light);
  scene.add(camera);

  const center = new THREE.Vector3().fromArray(info.boxMin).add(new THREE.Vector3().fromArray(info.boxMax)).multiplyScalar(0.5);
  const radius = 0.5 * new THREE.Vector3().fromArray(info.boxMax).sub(new THREE.Vector3().fromArray(info.boxMin)).length() || 1;
  const distance = (radius / Math.sin((0.5 * FOV * Math.PI) / 180)) * 1.05;
  if (params.get('eye')) {
    const e = params.get('eye').split(',').map(Number);
    if (e.length !== 3 || !e.every(Number.isFinite)) throw new Error('page parameter eye must be X,Y,Z');
    camera.position.fromArray(e);
  } else {
    camera.position.copy(center).add(new THREE.Vector3(0, 0, distance));
  }
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(center);
  controls.update();

  // Materials: shaded grey, one colour per level, one per node (a few hues in turn).
  const palette = (n, s, l) => Array.from({ length: n }, (_, i) =>
    new THREE.MeshLambertMaterial({ color: new THREE.Color().setHSL((i * 0.618034) % 1, s, l), flatShading: true }));
  const materials = {
    none: [new THREE.MeshLambertMaterial({ color: 0xc8c2b8, flatShading: true })],
    level: palette(info.levels, 0.55, 0.6),
    node: palette(24, 0.6, 0.6),
  };
  materials.group = materials.node;
  // The file's attributes: its texture and vertex colours (else grey), smooth shading by the stored
  // normals (else flat).
  const hasAttributes = info.colors || info.normals || info.texCoords;
  const useTexture = info.textureBytes > 0 && params.get('texture') !== '0';
  materials.vertex = [new THREE.MeshLambertMaterial({ color: info.colors || useTexture ? 0xffffff : 0xc8c2b8,
    vertexColors: info.colors, flatShading: !info.normals })];
  // The texture image from the file's TEXR chunk, read beside the first image (not before it):
  // decoded by the browser from a Blob URL, then put on the attributes' material.
  status.texture = useTexture ? 'loading' : 'none';
  const textureReady = !useTexture ? Promise.resolve() : reader.loadTexture().then(async (t) => {
    const url = URL.createObjectURL(new Blob([t.bytes], { type: t.mime }));
    try {
      const tex = await new THREE.TextureLoader().loadAsync(url);
      tex.colorSpace = THREE.SRGBColorSpace;
      tex.anisotropy = renderer.capabilities.getMaxAnisotropy();
      materials.vertex[0].map = tex;
      materials.vertex[0].needsUpdate = true;
      status.texture = `${t.name} (${t.mime}, ${t.bytes.length} bytes, ${tex.image.width} x ${tex.image.height})`;
      status.textureBytes = t.bytes.length;
    } finally {
      URL.revokeObjectURL(url);
    }
  });
  const modes = hasAttributes ? ['vertex', 'none', 'level', 'group', 'node'] : ['none', 'level', 'group', 'node'];
  let colorMode = params.get('color') || (hasAttributes ? 'vertex' : 'none');
  if (!modes.includes(colorMode)) throw new Error(`page parameter color must be one of ${modes.join(', ')}` +
    (colorMode === 'vertex' ? ' (the file has no colours or normals)' : ''));
  status.colorMode = colorMode;

  const view = () => {
    const h = renderer.getDrawingBufferSize(new THREE.Vector2()).y;
    return {
      eye: camera.position.toArray(),
      faceBudget: budget,
      cullBackFacing: params.get('cull') !== '0',
      projectionScale: h / (2 * Math.tan((0.5 * FOV * Math.PI) / 180)),
      maxPixelError: pixelError,
    };
  };

  // One mesh per unit on the GPU; its geometry groups are the unit's drawn nodes.
  const drawn = new Map();  // unit offset -> { mesh, unit }
  const refiner = new Refiner(reader);
  // The scene follows the cut; one update at a time (the refinement and the c key both ask).
  let updating = Promise.resolve();
  const updateScene = () => (updating = updating.then(updateSceneNow));
  async function updateSceneNow() {
    const byUnit = new Map();
    let minLevel = Infinity, maxLevel = -Infinity, worst = 0;
    for (const [id, culled] of refiner.cut) {
      const n = reader.node(id);
      minLevel = Math.min(minLevel, n.level);
      maxLevel = Math.max(maxLevel, n.level);
      if (culled) continue;
      worst = Math.max(worst, projectedError(n, refiner.view));
      const unit = await reader.loadUnit(id);
      if (!byUnit.has(unit.offset)) byUnit.set(unit.offset, { unit, nodes: [] });
      byUnit.get(unit.offset).nodes.push(id);
    }
    for (const [offset, d] of drawn)
      if (!byUnit.has(offset)) {
        scene.remove(d.mesh);
        d.mesh.geometry.dispose();
        drawn.delete(offset);
      }
    for (const [offset, { unit, nodes }] of byUnit) {
      let d = drawn.get(offset);
      if (!d) {
        const g = new THREE.BufferGeometry();
        g.setAttribute('position', new THREE.BufferAttribute(unit.positions, 3));
        const vc = unit.positions.length / 3;
        if (unit.attributes.colors) {  // sRGB bytes to three.js's linear working space
          const c = unit.attributes.colors, lin = new Float32Array(vc * 3);
          for (let i = 0; i < vc; ++i)
            for (let k = 0; k < 3; ++k) lin[i * 3 + k] = SRGB_TO_LINEAR[c[i * 4 + k]];
          g.setAttribute('color', new THREE.BufferAttribute(lin, 3));
        }
        if (unit.attributes.texCoords)
          g.setAttribute('uv', new THREE.BufferAttribute(decodeTexCoords(unit.attributes.texCoords, info.uvMin, info.uvMax), 2));
        if (unit.attributes.normals) {
          const q = new DataView(unit.attributes.normals.buffer), nrm = new Float32Array(vc * 3);
          for (let i = 0; i < vc; ++i) decodeNormal(q.getUint16(i * 4, true), q.getUint16(i * 4 + 2, true), nrm, i * 3);
          g.setAttribute('normal', new THREE.BufferAttribute(nrm, 3));
        }
        g.setIndex(new THREE.BufferAttribute(unit.corners, 1));
        g.computeBoundingSphere();
        d = { mesh: new THREE.Mesh(g, materials[colorMode]), unit };
        drawn.set(offset, d);
        scene.add(d.mesh);
      }
      d.mesh.material = materials[colorMode];
      d.mesh.geometry.clearGroups();
      nodes.sort((a, b) => a - b);
      for (const id of nodes) {
        const m = id - unit.firstNode, f0 = unit.faceStart[m], f1 = unit.faceStart[m + 1];
        const n = reader.node(id), k = materials.node.length;
        // group: the node's group within its level (roots: their own colour).
        const mat = colorMode === 'level' ? n.level : colorMode === 'node' ? id % k
          : colorMode === 'group' ? (n.group < 0 ? id : n.level * 7919 + n.group) % k : 0;
        d.mesh.geometry.addGroup(f0 * 3, (f1 - f0) * 3, mat);
      }
    }
    // Decoded units are kept for a restart from the roots, up to 256 MB; those drawn always.
    for (const offset of [...reader.unitSizes.keys()]) {
      if (reader.unitBytes <= 256e6) break;
      if (!drawn.has(offset)) reader.dropUnit(offset);
    }
    Object.assign(status, {
      cutFaces: refiner.faces, drawnFaces: refiner.drawnFaces, cutNodes: refiner.cut.size, minLevel, maxLevel,
      refinements: refiner.refinements, budgetReached: refiner.budgetReached, maxPixelError: worst,
      bytesFetched: reader.src.bytesFetched, requests: reader.src.requests,
    });
    showHud();
  }

  function showHud() {
    const kb = (b) => (b / 1024).toFixed(0) + ' KiB';
    hud.textContent =
      `${file}: ${info.inputFaces.toLocaleString()} faces, ${info.levels} levels, ${kb(info.fileBytes)}\n` +
      `cut: ${refiner.faces.toLocaleString()} faces (${refiner.drawnFaces.toLocaleString()} drawn), ` +
      `${refiner.cut.size} nodes, levels ${status.minLevel}-${status.maxLevel}, budget ${budget.toLocaleString()}\n` +
      `fetched: ${kb(reader.src.bytesFetched)} (${((100 * reader.src.bytesFetched) / info.fileBytes).toFixed(1)} %) ` +
      `in ${reader.src.requests} requests; first image after ${kb(status.firstImageBytes || 0)}\n` +
      `${status.state}${status.fps ? `, ${status.fps.toFixed(1)} frames/s` : ''}   colours: ${colorMode}` +
      `${hasAttributes ? ` (file: ${[info.colors && 'colour', info.normals && 'normals', info.texCoords && 'UV',
        useTexture && 'texture'].filter(Boolean).join(', ')})` : ''}` +
      `   (c: colours,${hasAttributes ? ' a: attributes/levels,' : ''} h: hide)`;
  }

  const render = () => renderer.render(scene, camera);
  let restart = false, wake = null;
  controls.addEventListener('change', () => {
    const d = camera.position.distanceTo(controls.target);
    camera.near = Math.max(d - 1.5 * radius, 0.01 * radius);
    camera.far = d + 1.5 * radius;
    camera.updateProjectionMatrix();
    render();
    restart = true;
    if (wake) wake();
  });
  controls.dispatchEvent({ type: 'change' });
  restart = false;
  window.addEventListener('resize', () => {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
    controls.dispatchEvent({ type: 'change' });
  });
  window.addEventListener('keydown', (e) => {
    if (e.key === 'c' || (e.key === 'a' && hasAttributes)) {
      colorMode = e.key === 'c' ? modes[(modes.indexOf(colorMode) + 1) % modes.length]
        : colorMode === 'vertex' ? 'level' : 'vertex';
      status.colorMode = colorMode;
      updateScene().then(render);
    } else if (e.key === 'h') {
      hud.style.display = hud.style.display === 'none' ? '' : 'none';
    }
  });

  // The first image: the roots.
  await refiner.start(view());
  await updateScene();
  render();
  await nextFrame();
  status.firstImageBytes = reader.src.bytesFetched;
  status.firstImageRequests = reader.src.requests;
  status.firstImageMs = performance.now() - t0;
  // The texture, once decoded, on the picture (before the refinement's first update at the latest).
  textureReady.then(render, fail);
  status.state = 'refining';
  status.views = 1;  // + 1 each time the view changes
  status.eye = camera.position.toArray();
  showHud();
  if (params.get('refine') === '0') {
    refiner.stopped = true;
  }
  const fpsFrames = numberParam('fps', 0);
  let shown = performance.now();
  for (;;) {
    if (restart) {
      restart = false;
      status.state = 'refining';
      status.views++;
      status.eye = camera.position.toArray();
      await refiner.start(view());
    }
    if (refiner.done()) {
      await updateScene();
      render();
      await nextFrame();
      if (status.state !== 'done') {
        await textureReady;  // 'done' shows the file's texture
        render();
        await nextFrame();
        status.doneMs = performance.now() - t0;
        status.doneBytes = reader.src.bytesFetched;
        if (fpsFrames > 0 && status.fps === undefined) await measureFps(fpsFrames);
        status.state = 'done';
        showHud();
        render();
        await nextFrame();
        document.title = 'ConeLOD web viewer [done]';
      }
      await new Promise((r) => (wake = r));  // until the view changes
      wake = null;
      continue;
    }
    // Expansions in slices; the picture is updated every 150 ms at most (drawing a frame costs
    // tens of ms in a software renderer: every slice would double the refinement's time).
    await refiner.step(16);
    if (!restart && performance.now() - shown > 150) {
      await updateScene();
      render();
      await nextFrame();
      shown = performance.now();
    }
  }

  // Frames per second drawing the cut (one frame per animation frame, so at most the display's
  // rate), and the time of one frame drawn and waited for (readPixels), which has no such cap.
  async function measureFps(frames) {
    const gl = renderer.getContext(), px = new Uint8Array(4);
    await nextFrame();
    let t = performance.now();
    for (let i = 0; i < frames; ++i) {
      render();
      await nextFrame();
    }
    status.fps = (frames * 1000) / (performance.now() - t);
    t = performance.now();
    for (let i = 0; i < frames; ++i) {
      render();
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    }
    status.frameMs = (performance.now() - t) / frames;
  }
}

main().catch(fail);
