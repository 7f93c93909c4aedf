// The cloud viewer: a PLY parser (ascii, binary little/big endian; any
// scalar vertex properties) and a three.js r111 point view with orbit
// controls. The scanner writes float x y z (mm, camera frame: z away from
// the camera, y down), float quality (fringe modulation), float intensity,
// float sigma_z (when the board gives the camera's noise) and uint pixel,
// with the organised size (firmware/core/src/point_cloud.cpp): normals come
// from the pixel grid and shade the points. While the view turns, fewer
// points are drawn (a frame within 50 ms, measured), all of them when it
// stops. What is on screen is also written on the viewer's element as
// data-* attributes (scan id, points, colouring, frame times): the page's
// state as the DOM shows it.

export const FppViewer = (function () {
  // Browsers slow down past a few hundred thousand points on phones.
  const MAX_POINTS = 300000;
  const CLEAR_COLOUR = 0x10141a;

  // PLY scalar types: byte size and DataView reader.
  const PLY_TYPES = {
    char: [1, 'getInt8'], int8: [1, 'getInt8'],
    uchar: [1, 'getUint8'], uint8: [1, 'getUint8'],
    short: [2, 'getInt16'], int16: [2, 'getInt16'],
    ushort: [2, 'getUint16'], uint16: [2, 'getUint16'],
    int: [4, 'getInt32'], int32: [4, 'getInt32'],
    uint: [4, 'getUint32'], uint32: [4, 'getUint32'],
    float: [4, 'getFloat32'], float32: [4, 'getFloat32'],
    double: [8, 'getFloat64'], float64: [8, 'getFloat64'],
  };

  // ---- PLY parsing -------------------------------------------------------

  // Where the header ends: the byte after "end_header" and its line break.
  function findHeaderEnd(bytes) {
    const limit = Math.min(bytes.length, 1 << 20);
    const head = new TextDecoder('latin1').decode(bytes.subarray(0, limit));
    const at = head.search(/end_header\r?\n/);
    if (at < 0) throw new Error('PLY: no end_header in the first MiB');
    const lineEnd = head.indexOf('\n', at);
    return { text: head.slice(0, at), bodyStart: lineEnd + 1 };
  }

  // The header: format and the elements in file order, each with its
  // properties (name, type, or list with count and item types).
  function parseHeader(text) {
    const lines = text.split(/\r?\n/);
    if (lines[0].trim() !== 'ply') throw new Error('PLY: the file does not start with "ply"');
    const header = { format: null, elements: [] };
    for (const raw of lines.slice(1)) {
      const words = raw.trim().split(/\s+/);
      const keyword = words[0];
      if (keyword === 'format') {
        header.format = words[1];
      } else if (keyword === 'obj_info' && /^organised_(width|height)$/.test(words[1])) {
        header[words[1]] = Number(words[2]);
      } else if (keyword === 'element') {
        const count = Number(words[2]);
        if (!Number.isInteger(count) || count < 0) throw new Error('PLY: bad count in "' + raw + '"');
        header.elements.push({ name: words[1], count: count, properties: [] });
      } else if (keyword === 'property') {
        const element = header.elements[header.elements.length - 1];
        if (!element) throw new Error('PLY: property before any element');
        if (words[1] === 'list') {
          element.properties.push({ name: words[4], list: true, countType: words[2], type: words[3] });
        } else {
          if (!PLY_TYPES[words[1]]) throw new Error('PLY: unknown property type "' + words[1] + '"');
          element.properties.push({ name: words[2], list: false, type: words[1] });
        }
      }
      // comment, obj_info and anything else: not needed to draw.
    }
    if (!['ascii', 'binary_little_endian', 'binary_big_endian'].includes(header.format))
      throw new Error('PLY: unsupported format "' + header.format + '"');
    return header;
  }

  // Every `stride`-th vertex's scalar properties, as one Float32Array per
  // property name ({x, y, z, quality, ...}).
  function parsePly(buffer, maxPoints) {
    const bytes = new Uint8Array(buffer);
    const { text, bodyStart } = findHeaderEnd(bytes);
    const header = parseHeader(text);
    const vertexIndex = header.elements.findIndex(e => e.name === 'vertex');
    if (vertexIndex < 0) throw new Error('PLY: no vertex element');
    const vertex = header.elements[vertexIndex];
    for (const axis of ['x', 'y', 'z'])
      if (!vertex.properties.some(p => p.name === axis && !p.list))
        throw new Error('PLY: the vertex element has no ' + axis + ' property');
    if (vertex.properties.some(p => p.list))
      throw new Error('PLY: list properties in the vertex element are not supported');
    const stride = Math.max(1, Math.ceil(vertex.count / (maxPoints || MAX_POINTS)));
    const kept = Math.ceil(vertex.count / stride);
    const columns = {};
    for (const p of vertex.properties) columns[p.name] = new Float32Array(kept);
    const organised = organisedGrid(header, vertex);
    if (header.format === 'ascii')
      readAscii(bytes, bodyStart, header, vertexIndex, stride, columns, organised);
    else
      readBinary(buffer, bodyStart, header, vertexIndex, stride, columns, organised);
    if (organised) addNormals(organised, columns);
    return { total: vertex.count, count: kept, stride: stride, columns: columns,
             properties: vertex.properties.map(p => p.name), format: header.format,
             normals: !!organised };
  }

  // The scanner's cloud is organised (obj_info organised_width / height and
  // a pixel property, row * width + column): every point's position goes
  // into a grid of the camera's pixels, so that normals come from the
  // neighbours of the full cloud even when one point in `stride` is drawn.
  function organisedGrid(header, vertex) {
    const w = header.organised_width, h = header.organised_height;
    if (!(w > 0 && h > 0 && w * h <= (1 << 25)) || !vertex.properties.some(p => p.name === 'pixel'))
      return null;
    const xyz = new Float32Array(3 * w * h).fill(NaN);
    return { width: w, height: h, xyz: xyz };
  }

  function putInGrid(grid, pixel, x, y, z) {
    if (!(pixel >= 0 && pixel < grid.width * grid.height)) return;
    grid.xyz[3 * pixel] = x;
    grid.xyz[3 * pixel + 1] = y;
    grid.xyz[3 * pixel + 2] = z;
  }

  // The unit normal at each drawn point, from the grid: the cross product of
  // the steps to its row and column neighbours (central where both sides
  // have points, one-sided at edges), turned towards the camera (-z).
  function addNormals(grid, columns) {
    const n = columns.x.length;
    const nx = new Float32Array(n), ny = new Float32Array(n), nz = new Float32Array(n);
    const { width: w, height: h, xyz } = grid;
    const d = [0, 0, 0, 0, 0, 0];
    function step(p, q, out, at) { // q - p, false when either is missing
      if (q < 0 || !(xyz[3 * q + 2] === xyz[3 * q + 2])) return false;
      out[at] = xyz[3 * q] - xyz[3 * p];
      out[at + 1] = xyz[3 * q + 1] - xyz[3 * p + 1];
      out[at + 2] = xyz[3 * q + 2] - xyz[3 * p + 2];
      return true;
    }
    for (let i = 0; i < n; ++i) {
      const p = columns.pixel[i];
      const col = p % w, row = (p - col) / w;
      let okU = false, okV = false;
      if (col + 1 < w && col > 0 && step(p - 1, p + 1, d, 0)) okU = true;
      else if (col + 1 < w && step(p, p + 1, d, 0)) okU = true;
      else if (col > 0 && step(p - 1, p, d, 0)) okU = true;
      if (row + 1 < h && row > 0 && step(p - w, p + w, d, 3)) okV = true;
      else if (row + 1 < h && step(p, p + w, d, 3)) okV = true;
      else if (row > 0 && step(p - w, p, d, 3)) okV = true;
      if (!okU || !okV) { nz[i] = -1; continue; }
      // (d0 d1 d2) along the row x (d3 d4 d5) down the column.
      let cx = d[1] * d[5] - d[2] * d[4], cy = d[2] * d[3] - d[0] * d[5], cz = d[0] * d[4] - d[1] * d[3];
      const len = Math.hypot(cx, cy, cz) || 1;
      if (cz > 0) { cx = -cx; cy = -cy; cz = -cz; }
      nx[i] = cx / len; ny[i] = cy / len; nz[i] = cz / len;
    }
    columns.nx = nx; columns.ny = ny; columns.nz = nz;
  }

  function readBinary(buffer, offset, header, vertexIndex, stride, columns, grid) {
    const little = header.format === 'binary_little_endian';
    const view = new DataView(buffer);
    // Skip the elements before the vertices (fixed-size records only).
    for (const element of header.elements.slice(0, vertexIndex)) {
      if (element.properties.some(p => p.list))
        throw new Error('PLY: element "' + element.name + '" before the vertices has list properties');
      offset += element.count * recordSize(element);
    }
    const vertex = header.elements[vertexIndex];
    const size = recordSize(vertex);
    if (offset + vertex.count * size > buffer.byteLength)
      throw new Error('PLY: the file is shorter than its ' + vertex.count + ' vertices');
    const fields = [];
    let at = 0;
    for (const p of vertex.properties) {
      fields.push({ column: columns[p.name], at: at, read: PLY_TYPES[p.type][1] });
      at += PLY_TYPES[p.type][0];
    }
    let out = 0;
    for (let i = 0; i < vertex.count; i += stride, ++out) {
      const base = offset + i * size;
      for (const f of fields) f.column[out] = view[f.read](base + f.at, little);
    }
    if (!grid) return;
    const pick = name => fields[vertex.properties.findIndex(p => p.name === name)];
    const [fx, fy, fz, fp] = ['x', 'y', 'z', 'pixel'].map(pick);
    for (let i = 0; i < vertex.count; ++i) {
      const base = offset + i * size;
      putInGrid(grid, view[fp.read](base + fp.at, little), view[fx.read](base + fx.at, little),
                view[fy.read](base + fy.at, little), view[fz.read](base + fz.at, little));
    }
  }

  function recordSize(element) {
    return element.properties.reduce((sum, p) => sum + PLY_TYPES[p.type][0], 0);
  }

  function readAscii(bytes, offset, header, vertexIndex, stride, columns, grid) {
    const body = new TextDecoder('latin1').decode(bytes.subarray(offset));
    const lines = body.split('\n');
    let line = 0;
    // Each record is one line, whatever its properties.
    for (const element of header.elements.slice(0, vertexIndex)) line += element.count;
    const vertex = header.elements[vertexIndex];
    const names = vertex.properties.map(p => p.name);
    let out = 0;
    for (let i = 0; i < vertex.count; i += stride, ++out) {
      const text = lines[line + i];
      if (text === undefined) throw new Error('PLY: the file is shorter than its ' + vertex.count + ' vertices');
      const words = text.trim().split(/\s+/);
      if (words.length < names.length) throw new Error('PLY: vertex ' + i + ' has too few values');
      for (let k = 0; k < names.length; ++k) columns[names[k]][out] = Number(words[k]);
    }
    if (!grid) return;
    const at = ['x', 'y', 'z', 'pixel'].map(name => names.indexOf(name));
    for (let i = 0; i < vertex.count; ++i) {
      const words = lines[line + i].trim().split(/\s+/);
      putInGrid(grid, Number(words[at[3]]), Number(words[at[0]]), Number(words[at[1]]), Number(words[at[2]]));
    }
  }

  // ---- colours -----------------------------------------------------------

  // Google's Turbo colour map, polynomial approximation; t in [0, 1].
  function turbo(t, rgb, at) {
    t = Math.min(1, Math.max(0, t));
    const t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t;
    rgb[at] = clamp01(0.13572138 + 4.61539260 * t - 42.66032258 * t2 + 132.13108234 * t3 - 152.94239396 * t4 + 59.28637943 * t5);
    rgb[at + 1] = clamp01(0.09140261 + 2.19418839 * t + 4.84296658 * t2 - 14.18503333 * t3 + 4.27729857 * t4 + 2.82956604 * t5);
    rgb[at + 2] = clamp01(0.10667330 + 12.64194608 * t - 60.58204836 * t2 + 110.36276771 * t3 - 89.90310912 * t4 + 27.34824973 * t5);
  }

  function clamp01(v) { return v < 0 ? 0 : v > 1 ? 1 : v; }

  // The 1st and 99th percentiles of finite values: a few outliers must not
  // squeeze every other point into one colour.
  function robustRange(values) {
    const step = Math.max(1, Math.floor(values.length / 20000));
    const sample = [];
    for (let i = 0; i < values.length; i += step) if (Number.isFinite(values[i])) sample.push(values[i]);
    if (sample.length === 0) return [0, 1];
    sample.sort((a, b) => a - b);
    const lo = sample[Math.floor(0.01 * (sample.length - 1))];
    const hi = sample[Math.ceil(0.99 * (sample.length - 1))];
    return hi > lo ? [lo, hi] : [lo, lo + 1];
  }

  // What each colouring shows, its unit and the column it reads.
  const MODES = {
    shaded: { label: 'shaded surface', column: null, unit: '' },
    depth: { label: 'depth z', column: 'z', unit: 'mm' },
    intensity: { label: 'intensity (texture)', column: 'intensity', unit: 'DN' },
    quality: { label: 'fringe modulation', column: 'quality', unit: 'DN' },
    sigma_z: { label: 'predicted sigma z', column: 'sigma_z', unit: 'mm' },
  };
  // Light from the viewer's upper left, in the camera frame (y down, z away).
  const LIGHT = (function () {
    const l = [-0.35, -0.45, -1], len = Math.hypot(l[0], l[1], l[2]);
    return l.map(v => v / len);
  })();
  // While the view turns, a frame may take this long; fewer points are drawn.
  const FRAME_BUDGET_MS = 50;
  const MIN_MOVING_POINTS = 2000;

  // The modes this cloud can show.
  function modesOf(parsed) {
    return Object.keys(MODES).filter(m =>
      m === 'shaded' ? parsed.normals : !!parsed.columns[MODES[m].column]);
  }

  // Lambert shading of point i, 0.12 .. 1 (1 without normals).
  function shadeOf(columns, i) {
    if (!columns.nx) return 1;
    const facing = columns.nx[i] * LIGHT[0] + columns.ny[i] * LIGHT[1] + columns.nz[i] * LIGHT[2];
    return 0.12 + 0.88 * Math.max(0, facing);
  }

  // The scale bar: at most this long on screen, a round length in mm.
  const SCALE_BAR_PX = 140;

  // The largest of 1, 2, 5 x 10^k mm not above `mm`.
  function roundLength(mm) {
    const decade = Math.pow(10, Math.floor(Math.log10(mm)));
    return [5, 2, 1].map(m => m * decade).find(l => l <= mm * (1 + 1e-9)) || decade;
  }

  function formatMm(mm) {
    return (mm >= 1 ? String(Math.round(mm)) : mm.toPrecision(1)) + ' mm';
  }

  function makeScaleBar(container) {
    const box = document.createElement('div');
    box.className = 'scale-bar';
    box.hidden = true;
    const line = document.createElement('span');
    line.className = 'scale-line';
    const text = document.createElement('span');
    text.className = 'scale-text';
    box.append(line, text);
    container.appendChild(box);
    return { box: box, line: line, text: text };
  }

  // A visiting order in which every prefix is an even sample of the cloud:
  // i -> i * P mod n with P prime and not a factor of n.
  function spreadOrder(n) {
    const order = new Uint32Array(n);
    let prime = 1;
    for (const p of [7919, 104729, 1299709, 15485863]) if (n % p !== 0) { prime = p; break; }
    for (let j = 0; j < n; ++j) order[j] = (j * prime) % n;
    return order;
  }

  // ---- the view ----------------------------------------------------------

  // A viewer in `container`; `onMessage(text)` reports problems to the page.
  function create(container, onMessage) {
    let renderer;
    try {
      // preserveDrawingBuffer: the page's test reads the canvas back.
      renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
    } catch (e) {
      onMessage('WebGL is not available in this browser: ' + e.message);
      return null;
    }
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setClearColor(CLEAR_COLOUR, 1);
    const canvas = renderer.domElement;
    canvas.setAttribute('role', 'img');
    canvas.setAttribute('aria-label', 'point cloud view: no cloud loaded');
    canvas.tabIndex = 0;
    container.appendChild(canvas);
    const scaleBar = makeScaleBar(container);

    const scene = new THREE.Scene();
    const camera = new THREE.PerspectiveCamera(45, 1, 1, 10000);
    const controls = new THREE.OrbitControls(camera, canvas);
    controls.screenSpacePanning = true;
    let points = null;
    let cloud = null;
    let order = null;
    let userMoved = false; // until the user turns the view, a resize re-frames the cloud
    let moving = false;
    let pointsPerMs = 0;   // measured drawing rate
    let pointSize = 2;
    let current = null;    // what show() drew: scan id, points, colouring
    const lod = { fullFrameMs: 0, fullPoints: 0, movingFrameMs: 0, movingPoints: 0 };
    const probe = new Uint8Array(4);

    // Draws `count` points (all when not given) and measures the frame.
    function draw(count) {
      if (!points) { renderer.render(scene, camera); publish(); updateScaleBar(); return; }
      const n = points.geometry.getAttribute('position').count;
      const drawn = Math.min(n, count || n);
      points.geometry.setDrawRange(0, drawn);
      const began = performance.now();
      renderer.render(scene, camera);
      // Reading a pixel waits for the frame (finish() need not, in software GL).
      const gl = renderer.getContext();
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, probe);
      const ms = performance.now() - began;
      if (drawn > 0 && ms > 0) pointsPerMs = pointsPerMs ? 0.7 * pointsPerMs + 0.3 * drawn / ms : drawn / ms;
      if (drawn === n) { lod.fullPoints = n; lod.fullFrameMs = ms; } else lod.movingFrameMs = ms;
      publish();
      updateScaleBar();
    }

    // The bar's length in mm at the orbit centre's depth (nearer parts look
    // larger): the view's height there is 2 d tan(fov / 2).
    function updateScaleBar() {
      if (!points || points.geometry.getAttribute('position').count === 0) { scaleBar.box.hidden = true; return; }
      const distance = camera.position.distanceTo(controls.target);
      const pxPerMm = container.clientHeight / (2 * distance * Math.tan(camera.fov * Math.PI / 360));
      const mm = roundLength(SCALE_BAR_PX / pxPerMm);
      scaleBar.line.style.width = (mm * pxPerMm).toFixed(1) + 'px';
      scaleBar.text.textContent = formatMm(mm) + ' at the centre';
      scaleBar.box.hidden = false;
    }
    function movingBudget() {
      const n = points ? points.geometry.getAttribute('position').count : 0;
      if (!pointsPerMs) return n;
      return Math.max(Math.min(n, MIN_MOVING_POINTS), Math.min(n, Math.floor(0.8 * FRAME_BUDGET_MS * pointsPerMs)));
    }
    controls.addEventListener('change', () => {
      if (moving) { lod.movingPoints = movingBudget(); draw(lod.movingPoints); } else draw();
    });
    controls.addEventListener('start', () => { userMoved = true; moving = true; });
    controls.addEventListener('end', () => { moving = false; draw(); });

    function resize() {
      const w = Math.max(1, container.clientWidth), h = Math.max(1, container.clientHeight);
      renderer.setSize(w, h, false);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
      if (points && !userMoved && points.geometry.getAttribute('position').count > 0) frame(points.geometry);
      draw();
    }
    if (window.ResizeObserver) new ResizeObserver(resize).observe(container);
    else window.addEventListener('resize', resize);
    resize();

    // Looks along +z with y down, as the scanner's camera does (the first
    // view is the camera's own picture), at the cloud's bounding box: its
    // near face fills the view with a margin.
    function frame(geometry) {
      geometry.computeBoundingBox();
      const box = geometry.boundingBox;
      const centre = box.getCenter(new THREE.Vector3());
      const half = box.getSize(new THREE.Vector3()).multiplyScalar(0.5);
      const tanHalfFov = Math.tan(camera.fov * Math.PI / 360);
      const fit = Math.max(half.y / tanHalfFov, half.x / (tanHalfFov * camera.aspect), 1e-3);
      const distance = half.z + 1.1 * fit;
      const reach = distance + half.length();
      camera.near = reach / 1000;
      camera.far = reach * 10;
      camera.up.set(0, -1, 0);
      camera.position.set(centre.x, centre.y, centre.z - distance);
      camera.updateProjectionMatrix();
      controls.target.copy(centre);
      controls.update();
    }

    // Fills the colour attribute for `mode`; the legend's range (null for
    // shaded grey).
    function applyColours(mode) {
      const columns = cloud.columns;
      const attribute = points.geometry.getAttribute('color');
      const rgb = attribute.array;
      const info = MODES[mode];
      const values = info.column ? columns[info.column] : null;
      const [lo, hi] = values ? robustRange(values) : [0, 1];
      const scale = 1 / (hi - lo);
      const tmp = [0, 0, 0];
      for (let j = 0; j < order.length; ++j) {
        const i = order[j];
        const shade = shadeOf(columns, i);
        if (mode === 'shaded' || mode === 'intensity') {
          const grey = mode === 'shaded' ? shade : clamp01((values[i] - lo) * scale);
          rgb[3 * j] = rgb[3 * j + 1] = rgb[3 * j + 2] = grey;
        } else {
          turbo((values[i] - lo) * scale, tmp, 0);
          const lit = 0.35 + 0.65 * shade; // the shape stays readable under the colours
          rgb[3 * j] = tmp[0] * lit; rgb[3 * j + 1] = tmp[1] * lit; rgb[3 * j + 2] = tmp[2] * lit;
        }
      }
      attribute.needsUpdate = true;
      return values && mode !== 'intensity' ? { lo: lo, hi: hi, unit: info.unit, label: info.label } : null;
    }

    // The drawn cloud and the last frame times on the container's data-*;
    // called every frame, so only a changed value is written (each write is
    // a DOM mutation).
    function publish() {
      const d = container.dataset;
      if (!current) {
        for (const key of Object.keys(d)) delete d[key];
        return;
      }
      const now = {
        scanId: current.scanId, points: current.points, total: current.total, colourBy: current.colourBy,
        normals: current.normals, clearColour: current.clearColour,
        fullFrameMs: lod.fullFrameMs.toFixed(1), fullPoints: lod.fullPoints,
        movingFrameMs: lod.movingFrameMs.toFixed(1), movingPoints: lod.movingPoints,
      };
      for (const [key, value] of Object.entries(now)) {
        const text = String(value);
        if (d[key] !== text) d[key] = text;
      }
    }

    function describe(mode, range) {
      canvas.setAttribute('aria-label', 'point cloud of ' + (current ? current.scanId : '') +
        ', ' + points.geometry.getAttribute('position').count + ' points, coloured by ' + MODES[mode].label +
        (range ? ' from ' + range.lo.toFixed(2) + ' to ' + range.hi.toFixed(2) + ' ' + range.unit : '') +
        '. Drag to turn, scroll to zoom.');
    }

    function clear() {
      if (points) {
        scene.remove(points);
        points.geometry.dispose();
        points.material.dispose();
      }
      points = null;
      cloud = null;
      current = null;
      canvas.setAttribute('aria-label', 'point cloud view: no cloud loaded');
      draw();
    }

    // Draws a parsed cloud; returns what was drawn.
    function show(parsed, scanId, mode) {
      clear();
      cloud = parsed;
      const n = parsed.count;
      order = spreadOrder(n);
      const positions = new Float32Array(3 * n);
      const { x, y, z } = parsed.columns;
      for (let j = 0; j < n; ++j) {
        const i = order[j];
        positions[3 * j] = x[i];
        positions[3 * j + 1] = y[i];
        positions[3 * j + 2] = z[i];
      }
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
      geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
      // Screen-sized points: the cloud stays solid at any zoom on any screen.
      const material = new THREE.PointsMaterial({
        size: pointSize * (window.devicePixelRatio || 1), sizeAttenuation: false,
        vertexColors: THREE.VertexColors,
      });
      points = new THREE.Points(geometry, material);
      scene.add(points);
      if (!modesOf(parsed).includes(mode)) mode = parsed.normals ? 'shaded' : 'depth';
      const range = applyColours(mode);
      userMoved = false;
      if (n > 0) frame(geometry);
      const drawn = { points: n, total: parsed.total, scanId: scanId, colourBy: mode, range: range,
                      modes: modesOf(parsed), normals: parsed.normals,
                      clearColour: '#' + CLEAR_COLOUR.toString(16).padStart(6, '0') };
      current = drawn;
      draw();
      describe(mode, range);
      return drawn;
    }

    function recolour(mode) {
      if (!points || !modesOf(cloud).includes(mode)) return null;
      const range = applyColours(mode);
      draw();
      current.colourBy = mode;
      current.range = range;
      publish();
      describe(mode, range);
      return range;
    }

    function setPointSize(size) {
      pointSize = size;
      if (points) { points.material.size = size * (window.devicePixelRatio || 1); draw(); }
    }

    function resetView() {
      userMoved = false;
      if (points && points.geometry.getAttribute('position').count > 0) frame(points.geometry);
      draw();
    }

    return { show: show, recolour: recolour, clear: clear, setPointSize: setPointSize,
             resetView: resetView, shown: () => current, modes: () => (cloud ? modesOf(cloud) : []),
             MODES: MODES };
  }

  return { create: create, parsePly: parsePly, MAX_POINTS: MAX_POINTS };
})();
