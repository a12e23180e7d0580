// The script of the page `umbra view` writes: draws the map's node layers
// (tools/viewer_data.hpp gives their format) as instanced boxes with three.js.
//
// The page carries one JSON block (#umbra-map: the map's numbers, the depths
// shown and which layers are embedded) and one base64 element per embedded
// layer (#layer-N, zlib-compressed). Only the layers of the depth on show are
// decoded and on the GPU; changing the depth drops them. Each layer is one
// draw call of a unit cube instanced n times, with a corner, an edge length
// per axis and (occupied layers of colored maps) a color per instance: 28
// bytes of GPU memory per node.
//
// A height cut (the "cut above" slider) hides every box whose bottom is at
// or above it, in the vertex shader, so that ceilings do not hide rooms; the
// page starts cut at the ceiling `umbra render` finds (data.ceilingCut), or
// above everything.
//
// For tests and scripts the page keeps window.umbraStats up to date (ready,
// depth, cut, drawn instances and their volume per state, errors) and offers
// window.umbraViewer.show(depth), .setVisible(state, on) and .setCut(z),
// which return promises that settle once the picture is drawn.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const STATES = ['occupied', 'free', 'unknown'];
// Free and unknown space are drawn see-through, a little shrunk, so that
// their boxes stay apart and the obstacles show through them.
const LOOK = {
  occupied: { color: [0.843, 0.188, 0.165], opacity: 1.0, shrink: 1.0 },
  free: { color: [0.353, 0.824, 0.478], opacity: 0.16, shrink: 0.9 },
  unknown: { color: [0.604, 0.478, 0.847], opacity: 0.12, shrink: 0.9 },
};

const vertexShader = /* glsl */ `
  attribute vec3 cornerAt;
  attribute vec3 edge;
  attribute vec3 rgb;
  uniform float colorMode;  // 0 height, 1 the map's colors, 2 flat
  uniform vec3 flatColor;
  uniform float zLow;
  uniform float zHigh;
  uniform float shrink;
  uniform float cutZ;  // nodes whose bottom is at or above this height are not drawn
  varying vec3 shaded;

  // umbra's height ramp (include/umbra/io/topdown_image.hpp): blue, cyan,
  // green, yellow, red.
  vec3 ramp(float t) {
    float s = clamp(t, 0.0, 1.0) * 4.0;
    vec3 c0 = vec3(48.0, 64.0, 200.0) / 255.0;
    vec3 c1 = vec3(0.0, 170.0, 210.0) / 255.0;
    vec3 c2 = vec3(60.0, 180.0, 75.0) / 255.0;
    vec3 c3 = vec3(240.0, 200.0, 40.0) / 255.0;
    vec3 c4 = vec3(215.0, 48.0, 39.0) / 255.0;
    if (s < 1.0) return mix(c0, c1, s);
    if (s < 2.0) return mix(c1, c2, s - 1.0);
    if (s < 3.0) return mix(c2, c3, s - 2.0);
    return mix(c3, c4, s - 3.0);
  }

  void main() {
    if (cornerAt.z >= cutZ) {
      gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: the whole box is dropped
      shaded = vec3(0.0);
      return;
    }
    vec3 centre = cornerAt + 0.5 * edge;
    vec3 world = centre + (position - 0.5) * edge * shrink;
    vec3 base = flatColor;
    if (colorMode < 0.5) {
      base = ramp(zHigh > zLow ? (centre.z - zLow) / (zHigh - zLow) : 0.0);
    } else if (colorMode < 1.5) {
      base = rgb;
    }
    // Boxes are never turned: the cube's normals are world normals.
    float light = 0.45 + 0.45 * max(dot(normal, normalize(vec3(0.35, 0.55, 1.0))), 0.0)
                + 0.2 * max(dot(normal, normalize(vec3(-0.6, -0.3, 0.2))), 0.0);
    shaded = base * light;
    gl_Position = projectionMatrix * modelViewMatrix * vec4(world, 1.0);
  }
`;

const fragmentShader = /* glsl */ `
  uniform float opacity;
  varying vec3 shaded;
  void main() { gl_FragColor = vec4(shaded, opacity); }
`;

const data = JSON.parse(document.getElementById('umbra-map').textContent);
const resolution = data.stats.resolution;
const stats = {
  ready: false,
  depth: null,
  cut: null,
  finestDepth: data.finestDepth,
  budget: data.budget,
  drawn: { occupied: 0, free: 0, unknown: 0 },
  volume: { occupied: 0, free: 0, unknown: 0 },
  instances: 0,
  frames: 0,
  errors: [],
};
window.umbraStats = stats;

const element = (id) => document.getElementById(id);

function reportError(message) {
  stats.errors.push(String(message));
  const line = document.createElement('div');
  line.className = 'error';
  line.textContent = 'error: ' + message;
  element('status').appendChild(line);
}
window.addEventListener('error', (event) => reportError(event.message));
window.addEventListener('unhandledrejection', (event) => reportError(event.reason));

// --- the numbers in the corner ------------------------------------------------

function fixed(value, digits = 2) {
  return Number(value).toFixed(digits);
}

function showNumbers() {
  const s = data.stats;
  element('title').textContent = data.title;
  document.title = 'umbra view: ' + data.title;
  const rows = [
    ['resolution', `${s.resolution} m, ${s.depth_levels} depth levels`],
    ['nodes', `${s.nodes.toLocaleString('en')} (inner ${s.inner_nodes.toLocaleString('en')}, inner leaf ${s.inner_leaf_nodes.toLocaleString('en')}, leaf ${s.leaf_nodes.toLocaleString('en')})`],
    ['memory', `${data.memory} (${s.memory_bytes.toLocaleString('en')} bytes)`],
    ['occupied', `${s.occupied_voxels.toLocaleString('en')} voxels, ${fixed(s.occupied_volume_m3, 3)} m³`],
    ['free', `${s.free_voxels.toLocaleString('en')} voxels, ${fixed(s.free_volume_m3, 3)} m³`],
  ];
  if (s.known_min) {
    rows.push(['known space', `(${s.known_min.map((v) => fixed(v)).join(', ')}) to (${s.known_max.map((v) => fixed(v)).join(', ')}) m`]);
  }
  const table = element('numbers');
  for (const [name, value] of rows) {
    const row = table.insertRow();
    row.insertCell().textContent = name;
    row.insertCell().textContent = value;
  }
}

// --- layers -------------------------------------------------------------------

const layersAt = new Map();  // depth -> {occupied, free, unknown} entries of data.layers
for (const layer of data.layers) {
  if (!layersAt.has(layer.depth)) layersAt.set(layer.depth, {});
  layersAt.get(layer.depth)[layer.state] = layer;
}
const depths = [...layersAt.keys()].sort((a, b) => a - b);

async function inflate(id) {
  const base64 = element(id).textContent.trim();
  const response = await fetch('data:application/octet-stream;base64,' + base64);
  const stream = response.body.pipeThrough(new DecompressionStream('deflate'));
  return new Response(stream).arrayBuffer();
}

const unitCube = new THREE.BoxGeometry(1, 1, 1).translate(0.5, 0.5, 0.5);

// The 30 low bits of a Morton code -> the 10 low bits of one axis (bits 0, 3, 6, ...).
function compact10(v) {
  v &= 0x09249249;
  v = (v ^ (v >>> 2)) & 0x030c30c3;
  v = (v ^ (v >>> 4)) & 0x0300f00f;
  v = (v ^ (v >>> 8)) & 0xff0000ff;
  v = (v ^ (v >>> 16)) & 0x000003ff;
  return v;
}

const TWO_30 = 1073741824;

/// A layer's instances: corners, edges and colors in metres from the known
/// space's lowest corner (clipped to the known space), their
/// total volume and height range. The format is tools/viewer_data.hpp's:
/// varint code deltas, depth bytes, 5-6-5 color columns.
async function decodeLayer(layer) {
  const n = layer.count;
  const bytes = new Uint8Array(await inflate(layer.id));
  const withColors = layer.state === 'occupied' && data.hasColor;
  const corners = new Float32Array(3 * n);
  const edges = new Float32Array(3 * n);
  const bottoms = new Float64Array(n);  // for the height cut
  const volumes = new Float64Array(n);  // m^3, from whole voxel counts
  let at = 0;
  let code = 0;
  const codes = new Float64Array(n);
  for (let i = 0; i < n; ++i) {
    // Codes stay below 2^51: a Number holds them exactly.
    let delta = 0;
    let scale = 1;
    for (;;) {
      if (at >= bytes.length) throw new Error(`layer ${layer.id} ends inside node ${i} of ${n}`);
      const byte = bytes[at++];
      delta += (byte & 0x7f) * scale;
      scale *= 128;
      if (byte < 0x80) break;
    }
    code += delta;
    codes[i] = code;
  }
  const expected = at + n + (withColors ? 3 * n : 0);
  if (bytes.length !== expected) {
    throw new Error(`layer ${layer.id} holds ${bytes.length} bytes, expected ${expected}`);
  }
  let volume = 0;
  let zLow = Infinity;
  let zHigh = -Infinity;
  const key = [0, 0, 0];
  for (let i = 0; i < n; ++i) {
    const high = Math.floor(codes[i] / TWO_30);
    const low = codes[i] - high * TWO_30;
    for (let axis = 0; axis < 3; ++axis) key[axis] = compact10(low >>> axis) + compact10(high >>> axis) * 1024;
    const size = 2 ** (layer.depth + bytes[at + i]);  // finest voxels
    let cells = 1;
    for (let axis = 0; axis < 3; ++axis) {
      // Clipped to the known space: unknown nodes and coarse ones reach beyond it.
      const first = Math.max(key[axis] * 2 ** layer.depth - data.origin[axis], 0);
      const end = Math.min(key[axis] * 2 ** layer.depth - data.origin[axis] + size, data.size[axis]);
      corners[3 * i + axis] = first * resolution;
      if (axis === 2) bottoms[i] = first * resolution;  // in double, for exact counts
      edges[3 * i + axis] = (end - first) * resolution;
      cells *= end - first;
    }
    volume += cells;
    volumes[i] = cells * resolution ** 3;
    const z = corners[3 * i + 2] + 0.5 * edges[3 * i + 2];
    zLow = Math.min(zLow, z);
    zHigh = Math.max(zHigh, z);
  }
  const colors = new Uint8Array(3 * n);
  if (withColors) {
    const base = at + n;
    const last = [0, 0, 0];
    const bits = [5, 6, 5];
    for (let i = 0; i < n; ++i) {
      for (let channel = 0; channel < 3; ++channel) {
        last[channel] = (last[channel] + bytes[base + channel * n + i]) & 0xff;
        const v = last[channel];
        // Back to 8 bits: the high bits repeated below (31 -> 255, 63 -> 255).
        colors[3 * i + channel] = (v << (8 - bits[channel])) | (v >> (2 * bits[channel] - 8));
      }
    }
  }
  return { count: n, corners, edges, colors, bottoms, volumes, volume: volume * resolution ** 3, zLow, zHigh };
}

function meshOf(state, decoded) {
  const geometry = new THREE.InstancedBufferGeometry();
  geometry.index = unitCube.index;
  geometry.setAttribute('position', unitCube.getAttribute('position'));
  geometry.setAttribute('normal', unitCube.getAttribute('normal'));
  geometry.setAttribute('cornerAt', new THREE.InstancedBufferAttribute(decoded.corners, 3));
  geometry.setAttribute('edge', new THREE.InstancedBufferAttribute(decoded.edges, 3));
  geometry.setAttribute('rgb', new THREE.InstancedBufferAttribute(decoded.colors, 3, true));
  geometry.instanceCount = decoded.count;
  const look = LOOK[state];
  const material = new THREE.ShaderMaterial({
    vertexShader,
    fragmentShader,
    uniforms: {
      colorMode: { value: 2 },
      flatColor: { value: new THREE.Vector3(...look.color) },
      zLow: { value: decoded.zLow },
      zHigh: { value: decoded.zHigh },
      shrink: { value: look.shrink },
      opacity: { value: look.opacity },
      cutZ: { value: cutScene() },
    },
    transparent: look.opacity < 1,
    depthWrite: look.opacity === 1,
  });
  const mesh = new THREE.Mesh(geometry, material);
  mesh.frustumCulled = false;  // the unit cube's bounds are not the instances'
  mesh.renderOrder = look.opacity < 1 ? 1 : 0;
  return mesh;
}

// --- the scene ------------------------------------------------------------------

const canvas = element('view');
let renderer;
const scene = new THREE.Scene();
const size = new THREE.Vector3(...(data.size || [1, 1, 1])).multiplyScalar(resolution);
const centre = size.clone().multiplyScalar(0.5);
const camera = new THREE.PerspectiveCamera(45, 1, 1, 2);
let controls;

function render() {
  if (!renderer) return;
  renderer.render(scene, camera);
  stats.frames += 1;
}

function fitToWindow() {
  // The canvas fills the room the panel leaves (page.html's flex layout).
  const width = Math.max(1, canvas.clientWidth);
  const height = Math.max(1, canvas.clientHeight);
  renderer.setSize(width, height, false);
  camera.aspect = width / Math.max(1, height);
  camera.updateProjectionMatrix();
  render();
}

function setUpScene() {
  renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0x15161c);
  const radius = Math.max(size.length() / 2, resolution);
  // A little inside the distance at which the bounding sphere fits: maps are
  // flat, and the sphere around them is mostly empty.
  const distance = (radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2))) * 0.8;
  camera.up.set(0, 0, 1);
  camera.near = distance / 1000;
  camera.far = distance * 10;
  camera.position.copy(centre).add(new THREE.Vector3(-1, -1.3, 0.9).normalize().multiplyScalar(distance));
  controls = new OrbitControls(camera, canvas);
  controls.target.copy(centre);
  controls.update();
  controls.addEventListener('change', render);
  window.addEventListener('resize', fitToWindow);
  fitToWindow();
}

// --- what is on show ---------------------------------------------------------------

const visible = { occupied: true, free: false, unknown: false };
// The height cut in map metres: boxes whose bottom is at or above it are hidden.
const knownLow = data.stats.known_min ? data.stats.known_min[2] : 0;
const knownHigh = data.stats.known_max ? data.stats.known_max[2] : 0;
let cut = data.ceilingCut === null || data.ceilingCut === undefined ? knownHigh : data.ceilingCut;
function cutScene() {
  return cut - knownLow;
}
let colorMode = 0;  // 0 height, 1 the map's colors
let current = { depth: null, meshes: {}, decoded: {} };
let request = 0;  // the latest show() wins when several overlap

function layerOf(depth, state) {
  return (layersAt.get(depth) || {})[state];
}

function applyColorMode() {
  for (const [state, mesh] of Object.entries(current.meshes)) {
    mesh.material.uniforms.colorMode.value = state === 'occupied' ? colorMode : 2;
  }
}

async function show(depth) {
  const mine = ++request;
  if (current.depth !== depth) {
    for (const mesh of Object.values(current.meshes)) {
      scene.remove(mesh);
      mesh.geometry.dispose();
      mesh.material.dispose();
    }
    current = { depth, meshes: {}, decoded: {} };
  }
  for (const state of STATES) {
    const layer = layerOf(depth, state);
    if (!visible[state] || !layer || !layer.id || current.meshes[state]) continue;
    const decoded = await decodeLayer(layer);
    if (mine !== request || current.depth !== depth) return;  // a newer request took over
    current.decoded[state] = decoded;
    current.meshes[state] = meshOf(state, decoded);
    scene.add(current.meshes[state]);
  }
  if (mine !== request) return;
  applyCut();
  applyColorMode();
  stats.depth = depth;
  describe(depth);
  render();
  stats.ready = true;
}

/// The boxes below the cut, per state: what the picture draws.
function countDrawn() {
  stats.instances = 0;
  const limit = cutScene();
  for (const state of STATES) {
    const mesh = current.meshes[state];
    if (mesh) mesh.visible = visible[state];
    const decoded = current.decoded[state];
    let count = 0;
    let volume = 0;
    if (mesh && visible[state]) {
      for (let i = 0; i < decoded.count; ++i) {
        if (decoded.bottoms[i] >= limit) continue;
        count += 1;
        volume += decoded.volumes[i];
      }
    }
    stats.drawn[state] = count;
    stats.volume[state] = volume;
    stats.instances += count;
  }
}

function applyCut() {
  for (const mesh of Object.values(current.meshes)) mesh.material.uniforms.cutZ.value = cutScene();
  stats.cut = cut;
  element('cut').value = cut;
  element('cut-label').textContent = cut >= knownHigh ? 'none' : `z ${fixed(cut)} m`;
  countDrawn();
}

function setCut(z) {
  cut = Math.min(Math.max(Number(z), knownLow), knownHigh);
  applyCut();
  if (current.depth !== null) describe(current.depth);
  render();
  return Promise.resolve();
}

function describe(depth) {
  const nodeSize = resolution * 2 ** depth;
  element('depth-label').textContent = `${depth} (${+nodeSize.toPrecision(4)} m nodes)`;
  for (const state of ['free', 'unknown']) {
    const layer = layerOf(depth, state);
    const box = element('show-' + state);
    const note = element(state + '-note');
    box.disabled = !layer || !layer.id;
    note.textContent = layer && !layer.id ? `(${layer.count.toLocaleString('en')} nodes: over the budget)` : '';
  }
  const status = element('status');
  status.textContent = '';
  const drawn = STATES.filter((s) => stats.drawn[s] > 0).map((s) => `${stats.drawn[s].toLocaleString('en')} ${s}`);
  const line = document.createElement('div');
  line.id = 'drawn';
  const below = cut < knownHigh ? ` below the cut at z ${fixed(cut)} m` : '';
  line.textContent = drawn.length ? `drawing ${drawn.join(', ')} nodes (${stats.instances.toLocaleString('en')} boxes)${below}` : `nothing to draw at this depth${below}`;
  status.appendChild(line);
  if (data.finestDepth > 0) {
    const note = document.createElement('div');
    note.className = 'note';
    note.textContent = data.depthZeroOccupied > data.budget
      ? `depth 0 holds ${data.depthZeroOccupied.toLocaleString('en')} occupied nodes, more than the budget of ` +
        `${data.budget.toLocaleString('en')} (umbra view --budget): the finest depth drawn is ${data.finestDepth}`
      : `a map of ${data.stats.depth_levels} depth levels starts at depth ${data.finestDepth} (the page's codes hold 17 levels)`;
    status.appendChild(note);
  }
  for (const message of stats.errors) {
    const line = document.createElement('div');
    line.className = 'error';
    line.textContent = 'error: ' + message;
    status.appendChild(line);
  }
}

function setVisible(state, on) {
  visible[state] = on;
  element('show-' + state).checked = on;
  return show(current.depth);
}

function wireControls() {
  const slider = element('depth');
  slider.min = depths[0];
  slider.max = depths[depths.length - 1];
  slider.value = depths[0];
  slider.addEventListener('input', () => show(Number(slider.value)));
  const cutSlider = element('cut');
  cutSlider.min = knownLow;
  cutSlider.max = knownHigh;
  cutSlider.step = resolution;
  cutSlider.value = cut;
  cutSlider.addEventListener('input', () => setCut(cutSlider.value));
  for (const state of STATES) {
    element('show-' + state).addEventListener('change', (event) => setVisible(state, event.target.checked));
  }
  const colors = element('color-mode');
  colors.disabled = !data.hasColor;
  colors.addEventListener('change', () => {
    colorMode = colors.value === 'rgb' ? 1 : 0;
    applyColorMode();
    render();
  });
}

/// The panel beside the picture folds to a strip; the picture takes the room.
function wirePanel() {
  const button = element('fold');
  button.addEventListener('click', () => {
    const folded = document.body.classList.toggle('folded');
    button.textContent = folded ? '>' : '<';
    button.title = folded ? 'show the panel' : 'hide the panel';
    if (renderer) fitToWindow();
  });
}

window.umbraViewer = {
  depths,
  show: (depth) => {
    element('depth').value = depth;
    return show(depth);
  },
  setVisible,
  setCut,
  fold: () => {
    element('fold').click();
    return Promise.resolve();
  },
};

showNumbers();
wirePanel();
try {
  setUpScene();
} catch (error) {
  reportError('cannot draw: WebGL is not available in this browser (' + error.message + ')');
}
if (depths.length === 0) {
  element('status').textContent = 'the map has no known space: nothing to draw';
  stats.ready = true;
} else if (renderer) {
  wireControls();
  show(depths[0]).catch((error) => reportError(error.message));
}
