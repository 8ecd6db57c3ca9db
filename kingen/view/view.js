// kingen's 3D view: draws a robot from its scene (kingen/view/scene.py's JSON, in the element
// #kingen-scene), answers each pose with the robot's routine compiled to WebAssembly (when the
// page holds one: window.kingenRoutine, set up by page.py from the JS glue) and writes what the
// routine computed into #kingen-joints as {"joints": [...], "warning": "...", "by": "..."}.
// Lengths in mm, angles in degrees on screen; joints in mm and radians in #kingen-joints.
// three.js is read from #kingen-three (its module source, imported from a Blob URL: no network).
"use strict";

const STATUS_COLOURS = {good: 0x4a7ab0, limits: 0xe08a00, singular: 0xb040c0, unreachable: 0xd02020};
const STATUS_WORDS = {good: "good", limits: "beyond its travel", singular: "singular",
                      unreachable: "unreachable"};
const DEG = Math.PI / 180;
const FORWARD_WORDS = {"-1": "the joints are not finite numbers", "-2": "no pose has them (an iterate unreachable or singular)",
                       "-4": "the pose found lies in another assembly mode than this pose (a singularity between)",
                       "-5": "no convergence within the routine's steps"};

// ---- poses and matrices (column-form H as nested arrays, as scene.py writes them) ----

function rotationRpy(roll, pitch, yaw) {  // R = Rz(yaw) Ry(pitch) Rx(roll), radians
  const [cr, sr, cp, sp, cy, sy] = [Math.cos(roll), Math.sin(roll), Math.cos(pitch), Math.sin(pitch),
                                    Math.cos(yaw), Math.sin(yaw)];
  return [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
          [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
          [-sp, cp * sr, cp * cr]];
}

function matrixFromPose(pose) {  // pose: x y z mm, roll pitch yaw degrees
  const r = rotationRpy(pose[3] * DEG, pose[4] * DEG, pose[5] * DEG);
  return [[...r[0], pose[0]], [...r[1], pose[1]], [...r[2], pose[2]], [0, 0, 0, 1]];
}

function poseFromMatrix(h) {
  const roll = Math.atan2(h[2][1], h[2][2]), pitch = Math.asin(Math.max(-1, Math.min(1, -h[2][0])));
  const yaw = Math.atan2(h[1][0], h[0][0]);
  return [h[0][3], h[1][3], h[2][3], roll / DEG, pitch / DEG, yaw / DEG];
}

const apply = (h, p) => [0, 1, 2].map(r => h[r][0] * p[0] + h[r][1] * p[1] + h[r][2] * p[2] + h[r][3]);
const turn = (m, p) => [0, 1, 2].map(r => m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2]);
const times = (a, b) => a.map((row, r) => b[0].map((_, c) => row.reduce((s, v, k) => s + v * b[k][c], 0)));
const add = (a, b) => a.map((v, i) => v + b[i]);
const scaled = (a, s) => a.map(v => v * s);
const sub = (a, b) => a.map((v, i) => v - b[i]);
const norm = a => Math.hypot(...a);

function rotationAbout(axis, angle) {  // Rodrigues, a unit axis
  const [x, y, z] = axis, c = Math.cos(angle), s = Math.sin(angle), t = 1 - c;
  return [[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
          [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
          [t * x * z - s * y, t * y * z + s * x, t * z * z + c]];
}

// ---- the machine's drawing at a pose, from the scene's model (scene.py's module docstring) ----

function baseSide(limb, q) {
  const f = limb.base_side;
  return [0, 1, 2].map(i => f.c[i] + q * f.a[i] + Math.cos(q) * f.u[i] + Math.sin(q) * f.v[i]);
}

function closure(model, platform, joints) {  // each limb's |P - B(q)| - l(q), mm
  return model.limbs.map((limb, i) => norm(sub(apply(platform, limb.platform_point), baseSide(limb, joints[i])))
                                      - (limb.passive[0] + limb.passive[1] * joints[i]));
}

// The pose (x y z mm, roll pitch yaw degrees) whose coordinates in `unknown` (indices) make the
// residuals residualOf(H) least in the least-squares sense, by Gauss-Newton from `start`, the
// others kept: the platform's pose the joints decide.
function solvePlatform(residualOf, start, unknown) {
  let pose = start.slice();
  for (let step = 0; step < 40 && unknown.length; step++) {
    const residual = residualOf(matrixFromPose(pose));
    const columns = unknown.map(k => {
      const moved = pose.slice();
      moved[k] += k < 3 ? 1e-4 : 1e-6;
      return residualOf(matrixFromPose(moved)).map((v, i) => (v - residual[i]) / (moved[k] - pose[k]));
    });
    const n = unknown.length, normal = [], right = [];
    for (let a = 0; a < n; a++) {
      normal.push(columns.map(col => col.reduce((s, v, i) => s + v * columns[a][i], 0)));
      right.push(-columns[a].reduce((s, v, i) => s + v * residual[i], 0));
    }
    const delta = gauss(normal, right);
    if (!delta) break;
    unknown.forEach((k, a) => { pose[k] += delta[a]; });
    if (norm(delta) < 1e-11) break;
  }
  return pose;
}

// The wrist's rotations (base frame) before each of its joints, then after the last, for the
// platform's rotation (3 x 3) and the wrist's joints (radians, their readings).
function wristTurns(wrist, rotation, joints) {
  const turns = [rotation];
  wrist.axes.forEach((axis, k) => { turns.push(times(turns[k], rotationAbout(axis, joints[k] + wrist.zero[k]))); });
  return turns;
}

const rotationOf = h => h.slice(0, 3).map(row => row.slice(0, 3));

function gauss(a, b) {  // a x = b by elimination with partial pivoting; null when singular
  const n = b.length, m = a.map((row, i) => [...row, b[i]]);
  for (let c = 0; c < n; c++) {
    let p = c;
    for (let r = c + 1; r < n; r++) if (Math.abs(m[r][c]) > Math.abs(m[p][c])) p = r;
    if (Math.abs(m[p][c]) < 1e-300) return null;
    [m[c], m[p]] = [m[p], m[c]];
    for (let r = c + 1; r < n; r++) {
      const f = m[r][c] / m[c][c];
      for (let k = c; k <= n; k++) m[r][k] -= f * m[c][k];
    }
  }
  const x = new Array(n).fill(0);
  for (let r = n - 1; r >= 0; r--) x[r] = (m[r][n] - m[r].slice(r + 1, n).reduce((s, v, i) => s + v * x[r + 1 + i], 0)) / m[r][r];
  return x;
}

// Whether joint `index` at q (mm, radians) is beyond its travel (scene.travel: mm or degrees, a
// side without a limit null).
function beyondTravel(scene, index, q) {
  const travel = scene.travel[index], unit = scene.joint_units[index] === "rad" ? DEG : 1;
  return Boolean(travel) && ((travel[0] !== null && q < travel[0] * unit - 1e-12)
                             || (travel[1] !== null && q > travel[1] * unit + 1e-12));
}

// A limb's colour key (scene.py's machine): unreachable where its link cannot close, beyond its
// travel, singular where the posture is and the link is within scene.singular_across (the cosine
// of its angle) of square to its base side's motion (a rail's or a crank's radicand near 0).
function limbStatus(scene, index, q, residual, warning, across) {
  if (scene.model.limbs[index].exact && Math.abs(residual) > 1e-6 * scene.size) return "unreachable";
  if (beyondTravel(scene, index, q)) return "limits";
  return warning === "WARN_SINGULAR_SOLUTION" && across <= scene.singular_across ? "singular" : "good";
}

// The drawing ({platform, limbs, tool, status}, scene.py's machine) for a pose the page asked for
// (x y z mm, roll pitch yaw degrees), the routine's joints and warning; `previous` seeds the
// platform's pose on machines whose platform pose the joints decide.
function drawingAt(scene, pose, joints, warning, previous) {
  const model = scene.model, wrist = model.wrist, asked = matrixFromPose(pose);
  let platform;
  const legs = joints.slice(0, model.limbs.length), seed = poseFromMatrix(previous.platform);
  if (wrist) {  // the wrist centre from the tool; the platform's rotation from the legs and the tool's rotation
    const axis = [asked[0][2], asked[1][2], asked[2][2]], tip = [asked[0][3], asked[1][3], asked[2][3]];
    const centre = wrist.whole_pose ? sub(tip, turn(asked, wrist.tip)) : sub(tip, scaled(axis, wrist.reach));
    const columns = wrist.whole_pose ? [0, 1, 2] : [2], wristJoints = joints.slice(model.limbs.length);
    const residualOf = h => {
      const tool = times(wristTurns(wrist, rotationOf(h), wristJoints).at(-1), rotationOf(wrist.tool));
      const missed = columns.flatMap(c => [0, 1, 2].map(r => (tool[r][c] - asked[r][c]) * scene.size));
      return [...closure(model, h, legs), ...missed];
    };
    platform = matrixFromPose(solvePlatform(residualOf, [...centre, ...seed.slice(3)], [3, 4, 5]));
  } else if (scene.free.length < 6 && closure(model, asked, legs).some(v => Math.abs(v) > 1e-9 * scene.size)) {
    // a pose that is not the machine's (its routine's machine pose not at hand): its other coordinates from the legs
    const unknown = [0, 1, 2, 3, 4, 5].filter(k => !scene.free.includes(scene.coordinates[k]));
    platform = matrixFromPose(solvePlatform(h => closure(model, h, legs), pose.map((v, k) => unknown.includes(k) ? seed[k] : v),
                                            unknown));
  } else {
    platform = asked;
  }
  const residuals = closure(model, platform, joints);
  const limbs = model.limbs.map((limb, i) => {
    const point = apply(platform, limb.platform_point), base = baseSide(limb, joints[i]);
    const link = sub(point, base), rate = [0, 1, 2].map(k => limb.base_side.a[k] - Math.sin(joints[i]) * limb.base_side.u[k]
                                                            + Math.cos(joints[i]) * limb.base_side.v[k]);
    const across = norm(rate) > 0 ? Math.abs(link.reduce((s, v, k) => s + v * rate[k], 0)) / (norm(link) * norm(rate)) : 1;
    return {base_side: base, platform_point: point, status: limbStatus(scene, i, joints[i], residuals[i], warning, across)};
  });
  let tool = null;
  if (wrist) {
    const turned = wristTurns(wrist, rotationOf(platform), joints.slice(model.limbs.length)).at(-1);
    const r = times(turned, rotationOf(wrist.tool));
    const origin = add([platform[0][3], platform[1][3], platform[2][3]], turn(turned, wrist.tool.slice(0, 3).map(row => row[3])));
    tool = [[...r[0], origin[0]], [...r[1], origin[1]], [...r[2], origin[2]], [0, 0, 0, 1]];
  }
  return {platform, limbs, tool, status: warning};
}

// A carriage's rail as drawn (base frame, mm): its ends at the joint's travel, a side without a
// limit 100 mm beyond both 0 and the joint's value q.
function railEnds(limb, travel, q) {
  return [baseSide(limb, travel?.[0] ?? Math.min(0, q) - 100), baseSide(limb, travel?.[1] ?? Math.max(0, q) + 100)];
}

// ---- text ----

function valueDigits(scene, index, value) {  // a joint's value in mm or degrees to 3 decimals, no -0.000
  const shown = scene.joint_units[index] === "rad" ? value / DEG : value;
  return (Math.abs(shown) < 5e-4 ? 0 : shown).toFixed(3);
}

function valueText(scene, index, value) {
  return `${valueDigits(scene, index, value)}${scene.joint_units[index] === "rad" ? "°" : " mm"}`;
}

function travelText(scene, index) {  // "a to b mm", "from a mm", "up to b°", or "no travel given"
  const travel = scene.travel[index], unit = scene.joint_units[index] === "rad" ? "°" : " mm";
  if (!travel) return "no travel given";
  if (travel[0] === null) return `up to ${travel[1]}${unit}`;
  return travel[1] === null ? `from ${travel[0]}${unit}` : `${travel[0]} to ${travel[1]}${unit}`;
}

const bothEnds = travel => Boolean(travel) && travel[0] !== null && travel[1] !== null;

// ---- three.js drawing ----

async function loadThree() {
  if (!window.kingenThree) {
    const source = document.getElementById("kingen-three").textContent;
    window.kingenThree = import(URL.createObjectURL(new Blob([source], {type: "text/javascript"})));
  }
  return window.kingenThree;
}

class Drawing {
  // One machine drawn (the machine, or a translucent ghost): cylinders between points, balls and
  // plates. Each draw() makes the same calls in the same order, so its meshes are kept and moved
  // (shared unit geometries, one material per colour), not made again.
  constructor(THREE, scene, group, opacity) {
    this.THREE = THREE;
    this.scene = scene;
    this.group = group;
    this.opacity = opacity;
    this.radius = scene.size / 150;
    this.meshes = [];
    this.used = 0;
    this.materials = new Map();
    this.cylinder = new THREE.CylinderGeometry(1, 1, 1, 12);
    this.sphere = new THREE.SphereGeometry(1, 16, 12);
  }

  material(colour, opacity) {
    const key = `${colour}/${opacity}`;
    if (!this.materials.has(key)) {
      const {THREE} = this;
      this.materials.set(key, new THREE.MeshStandardMaterial({color: colour, metalness: 0.2, roughness: 0.6, side: THREE.DoubleSide,
                                                              transparent: opacity < 1, opacity, depthWrite: opacity === 1}));
    }
    return this.materials.get(key);
  }

  mesh(kind, make) {  // the next mesh of this draw: the kept one, or a new one
    let mesh = this.meshes[this.used];
    if (!mesh || mesh.userData.kind !== kind) {
      if (mesh) this.group.remove(mesh);
      mesh = make();
      mesh.userData.kind = kind;
      this.meshes[this.used] = mesh;
      this.group.add(mesh);
    }
    mesh.visible = true;
    this.used += 1;
    return mesh;
  }

  rod(a, b, radius, colour) {
    const {THREE} = this, length = norm(sub(b, a));
    const mesh = this.mesh("rod", () => new THREE.Mesh(this.cylinder));
    mesh.material = this.material(colour, this.opacity);
    mesh.scale.set(radius, Math.max(length, 1e-9), radius);
    mesh.position.set(...scaled(add(a, b), 0.5));
    if (length > 0) mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), new THREE.Vector3(...scaled(sub(b, a), 1 / length)));
  }

  ball(p, radius, colour) {
    const {THREE} = this, mesh = this.mesh("ball", () => new THREE.Mesh(this.sphere));
    mesh.material = this.material(colour, this.opacity);
    mesh.scale.set(radius, radius, radius);
    mesh.position.set(...p);
  }

  polygon(points, colour, opacity) {  // a flat plate through points (ordered about their centre)
    const {THREE} = this;
    const centre = scaled(points.reduce(add, [0, 0, 0]), 1 / points.length);
    let normal = [0, 0, 0];
    for (let i = 0; i < points.length; i++) {
      const a = sub(points[i], centre), b = sub(points[(i + 1) % points.length], centre);
      const cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
      normal = add(normal, norm(cross) > 0 && cross[2] * (normal[2] || 1) < 0 ? scaled(cross, -1) : cross);
    }
    if (norm(normal) === 0) normal = [0, 0, 1];
    normal = scaled(normal, 1 / norm(normal));
    const e1 = norm(sub(points[0], centre)) > 0 ? sub(points[0], centre) : [1, 0, 0];
    const u = scaled(e1, 1 / norm(e1)), v = [normal[1] * u[2] - normal[2] * u[1], normal[2] * u[0] - normal[0] * u[2],
                                             normal[0] * u[1] - normal[1] * u[0]];
    const ordered = points.map(p => [Math.atan2(...[v, u].map(w => sub(p, centre).reduce((s, x, k) => s + x * w[k], 0))), p])
      .sort((a, b) => a[0] - b[0]).map(pair => pair[1]);
    const vertices = [];
    for (let i = 0; i < ordered.length; i++) vertices.push(...centre, ...ordered[i], ...ordered[(i + 1) % ordered.length]);
    const mesh = this.mesh("plate", () => new THREE.Mesh(new THREE.BufferGeometry()));
    const kept = mesh.geometry.getAttribute("position");
    if (kept && kept.array.length === vertices.length) {  // the same buffer, its numbers replaced
      kept.array.set(vertices);
      kept.needsUpdate = true;
    } else {
      mesh.geometry.dispose();
      mesh.geometry.setAttribute("position", new THREE.Float32BufferAttribute(vertices, 3));
    }
    mesh.geometry.computeVertexNormals();
    mesh.material = this.material(colour, Math.min(this.opacity, opacity));
    for (let i = 0; i < ordered.length; i++) this.rod(ordered[i], ordered[(i + 1) % ordered.length], this.radius * 0.6, colour);
  }

  // The base (its fixed joints and rails), the limbs in their status's colours, the platform,
  // the passive leg, the wrist and tool: from a drawing (scene.py's machine) and the joints.
  draw(drawing, joints) {
    this.used = 0;
    const model = this.scene.model, r = this.radius, platformColour = 0x707880;
    const pivots = model.limbs.map(limb => limb.pivot);
    if (pivots.length >= 3) this.polygon(pivots, 0x9aa0a6, 0.35);
    model.limbs.forEach((limb, i) => {
      const shown = drawing.limbs[i], colour = STATUS_COLOURS[shown.status] || STATUS_COLOURS.good;
      const travel = this.scene.travel[i];
      if (limb.actuator === "carriage") {
        this.rod(...railEnds(limb, travel, joints[i]), r * 0.8, 0x5a5f66);
        this.ball(shown.base_side, r * 2.2, colour);
      } else if (limb.actuator === "arm") {
        this.ball(limb.pivot, r * 1.8, 0x5a5f66);
        this.rod(limb.pivot, shown.base_side, r * 1.5, colour);
      } else {
        const link = sub(shown.platform_point, shown.base_side), length = norm(link);
        const body = Math.min(length, Math.max(limb.passive[0], length / 2));
        this.rod(shown.base_side, add(shown.base_side, scaled(link, body / Math.max(length, 1e-9) * 0.55)), r * 1.6, colour);
      }
      this.rod(shown.base_side, shown.platform_point, r * 0.9, colour);
      this.ball(shown.base_side, r * 1.2, 0x40454a);
      this.ball(shown.platform_point, r * 1.2, 0x40454a);
    });
    const corners = drawing.limbs.map(limb => limb.platform_point);
    const origin = [drawing.platform[0][3], drawing.platform[1][3], drawing.platform[2][3]];
    if (corners.length >= 3) this.polygon(corners, drawing.status === "WARN_GOOD_SOLUTION" ? platformColour : 0xd08080, 0.75);
    if (model.passive_leg) this.rod(model.passive_leg.base_point, origin, r * 2.2, 0x808890);
    const middle = scaled(corners.reduce(add, [0, 0, 0]), 1 / Math.max(corners.length, 1));
    if (corners.length && norm(sub(middle, origin)) > r) this.rod(middle, origin, r * 2.4, platformColour);
    if (model.wrist) {  // each wrist axis, turned by the joints before it, through the wrist centre
      const turns = wristTurns(model.wrist, rotationOf(drawing.platform), joints.slice(model.limbs.length));
      model.wrist.axes.forEach((axis, k) => {
        const along = scaled(turn(turns[k], axis), this.scene.size * 0.05);
        this.rod(sub(origin, along), add(origin, along), r * 1.8, 0x404850);
      });
    }
    if (drawing.tool) {
      const tip = [drawing.tool[0][3], drawing.tool[1][3], drawing.tool[2][3]];
      this.ball(origin, r * 2.5, 0x5a5f66);
      this.rod(origin, tip, r * 1.4, 0xc8a040);
    }
    this.frame(drawing.tool || drawing.platform, r * 12);
    for (const mesh of this.meshes.slice(this.used)) mesh.visible = false;
  }

  frame(h, length) {  // the tool (or platform) frame: x red, y green, z blue
    const origin = [h[0][3], h[1][3], h[2][3]];
    [0xd03030, 0x30a030, 0x3050d0].forEach((colour, k) => {
      this.rod(origin, add(origin, scaled([h[0][k], h[1][k], h[2][k]], length)), this.radius * 0.5, colour);
    });
  }
}

// ---- the page ----

// #pose=x,y,z,roll,pitch,yaw&posture=K, or #joints=q1,...,qn&posture=K, for a scene: what it
// asks ({pose, joints, posture, bench}) and, in `problems`, each part left out and why.
function parseFragment(hash, scene) {
  const found = {problems: []};
  let text = hash.replace(/^#/, "");
  try { text = decodeURIComponent(text); } catch (error) { found.problems.push(`${text} is not a well-formed address`); return found; }
  for (const part of text ? text.split("&") : []) {
    const [key, value = ""] = part.split("=");
    const numbers = value.split(",").map(v => (v.trim() === "" ? NaN : Number(v)));
    if (key === "pose" || key === "joints") {
      const count = key === "pose" ? 6 : scene.joint_names.length;
      if (numbers.length === count && numbers.every(Number.isFinite)) found[key] = numbers;
      else found.problems.push(`${key}=${value} is not ${count} numbers`);
    } else if (key === "posture" || key === "bench") {
      const number = /^\d+$/.test(value) ? Number(value) : NaN;
      const postures = scene.postures === 1 ? "the robot has posture 0 only" : `the robot's are 0 to ${scene.postures - 1}`;
      if (key === "posture" && !(number < scene.postures)) found.problems.push(`posture=${value} is not a posture (${postures})`);
      else if (Number.isInteger(number)) found[key] = number;
      else found.problems.push(`bench=${value} is not a count`);
    } else {
      found.problems.push(`"${part}" is not pose=, joints= or posture=`);
    }
  }
  return found;
}

class View {
  constructor(root, scene, THREE) {
    this.root = root;
    this.scene = scene;
    this.THREE = THREE;
    this.routine = window.kingenRoutine || null;
    this.pose = scene.pose.slice();
    this.posture = scene.posture;
    this.joints = scene.joints.slice();
    this.warning = scene.warning;
    this.drawn = scene.machine;
    this.times = [];
    this.routineTimes = [];
    this.setUpRenderer();
    this.setUpControls();
    this.setUpOverlays();
  }

  setUpRenderer() {
    const {THREE, scene} = this, canvas = this.root.querySelector(".kingen-canvas");
    this.renderer = new THREE.WebGLRenderer({canvas, antialias: true, preserveDrawingBuffer: true});
    this.renderer.setClearColor(0xf4f5f7);
    this.world = new THREE.Scene();
    this.world.add(new THREE.AmbientLight(0xffffff, 1.2));
    const light = new THREE.DirectionalLight(0xffffff, 1.6);
    light.position.set(1, -2, 3);
    this.world.add(light);
    this.camera = new THREE.PerspectiveCamera(35, 1, scene.size / 100, scene.size * 100);
    this.camera.up.set(0, 0, 1);
    this.machineGroup = new THREE.Group();
    this.world.add(this.machineGroup);
    this.machine = new Drawing(THREE, scene, this.machineGroup, 1);
    const base = new THREE.Group();  // the base frame at its origin: x red, y green, z blue
    this.world.add(base);
    new Drawing(THREE, scene, base, 1).frame([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], scene.size / 6);
    const points = [...scene.model.limbs.map(l => l.pivot), ...scene.machine.limbs.map(l => l.platform_point),
                    ...scene.machine.limbs.map(l => l.base_side)];
    scene.model.limbs.forEach((limb, i) => {  // a rail whole: the view opens with every part of the machine in sight
      if (limb.actuator === "carriage") points.push(...railEnds(limb, scene.travel[i], scene.joints[i]));
    });
    if (scene.machine.tool) points.push([0, 1, 2].map(r => scene.machine.tool[r][3]));
    for (const arrow of scene.arrows || []) points.push(arrow.origin, add(arrow.origin, arrow.vector));
    points.push(...(scene.points || []).map(point => point.position), ...(scene.surface ? scene.surface.vertices : []));
    const centre = scaled(points.reduce(add, [0, 0, 0]), 1 / points.length);
    const radius = Math.max(...points.map(p => norm(sub(p, centre)))) || scene.size;
    this.orbit = {target: centre, distance: radius * 4.4, azimuth: -60 * DEG, elevation: 25 * DEG};
    this.resize();
    new ResizeObserver(() => { this.resize(); this.render(); }).observe(canvas);
  }

  resize() {
    const canvas = this.renderer.domElement, width = canvas.clientWidth || 640, height = canvas.clientHeight || 480;
    this.renderer.setSize(width, height, false);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
  }

  setUpControls() {
    const canvas = this.renderer.domElement;
    let last = null;
    canvas.addEventListener("pointerdown", e => { last = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener("pointerup", () => { last = null; });
    canvas.addEventListener("pointermove", e => {
      if (!last) return;
      this.orbit.azimuth -= (e.clientX - last[0]) * 0.01;
      this.orbit.elevation = Math.max(-1.5, Math.min(1.5, this.orbit.elevation + (e.clientY - last[1]) * 0.01));
      last = [e.clientX, e.clientY];
      this.render();
    });
    const home = {...this.orbit};
    canvas.addEventListener("dblclick", () => { Object.assign(this.orbit, home); this.render(); });
    canvas.addEventListener("wheel", e => {
      e.preventDefault();
      this.orbit.distance *= Math.exp(e.deltaY * 0.001);
      this.render();
    }, {passive: false});
    const form = this.root.querySelector(".kingen-pose");
    this.fields = {};
    this.scene.coordinates.forEach((name, k) => {
      const free = this.scene.free.includes(name), home = this.scene.region.home[k];
      const span = Math.max(this.scene.region.range[k] * 1.5, k < 3 ? 10 : 5);
      const row = document.createElement("label");
      row.className = "kingen-coordinate";
      row.innerHTML = `<span>${name} (${k < 3 ? "mm" : "°"})</span>`;
      const slider = Object.assign(document.createElement("input"), {type: "range", min: home - span, max: home + span,
                                                                      step: k < 3 ? 0.1 : 0.05, value: this.pose[k]});
      const number = Object.assign(document.createElement("input"), {type: "number", step: "any", value: this.pose[k]});
      slider.dataset.coordinate = number.dataset.coordinate = name;
      const enabled = free && this.routine !== null;
      slider.disabled = number.disabled = !enabled;
      slider.addEventListener("input", () => { number.value = slider.value; this.change(k, Number(slider.value)); });
      number.addEventListener("change", () => {
        if (number.value === "" || !Number.isFinite(Number(number.value))) { number.value = this.pose[k]; return; }
        slider.value = number.value;
        this.change(k, Number(number.value));
      });
      row.append(slider, number);
      form.append(row);
      this.fields[name] = [slider, number];
    });
    const posture = this.root.querySelector(".kingen-posture");
    for (let k = 0; k < this.scene.postures; k++) {
      const branches = (this.scene.posture_branches || [])[k];
      posture.append(new Option(branches && branches !== "-" ? `${k} (branches ${branches})` : String(k), String(k)));
    }
    posture.value = String(this.posture);
    posture.disabled = this.routine === null;
    posture.addEventListener("change", () => { this.posture = Number(posture.value); this.update(); });
    const note = this.root.querySelector(".kingen-note");
    if (this.routine === null) note.textContent = this.scene.no_routine || "The routine is not in this page: the machine is drawn where kingen computed it.";
    else note.textContent = `Every change is answered by the routine ${this.routine.prefix}, the generated C library compiled to WebAssembly inside this page.`;
  }

  setUpOverlays() {
    const {THREE, scene} = this, size = scene.size;
    const labels = this.root.querySelector(".kingen-labels");
    this.labels = scene.joint_names.map(() => labels.appendChild(document.createElement("div")));
    this.extraLabels = [];
    const label = (position, text) => {
      const div = labels.appendChild(document.createElement("div"));
      div.className = "kingen-label kingen-extra";
      div.textContent = text;
      this.extraLabels.push([position, div]);
    };
    for (const arrow of scene.arrows || []) {
      const length = norm(arrow.vector);
      if (length > 0) {
        this.world.add(new THREE.ArrowHelper(new THREE.Vector3(...scaled(arrow.vector, 1 / length)),
                                             new THREE.Vector3(...arrow.origin), length, 0xd02060, size / 40, size / 80));
      }
      if (arrow.label) label(add(arrow.origin, arrow.vector), arrow.label);
    }
    for (const point of scene.points || []) {
      const mesh = new THREE.Mesh(new THREE.SphereGeometry(size / 90, 12, 8), new THREE.MeshStandardMaterial({color: 0x208060}));
      mesh.position.set(...point.position);
      this.world.add(mesh);
      if (point.label) label(point.position, point.label);
    }
    if (scene.surface) {
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute("position", new THREE.Float32BufferAttribute(scene.surface.vertices.flat(), 3));
      geometry.setIndex(scene.surface.triangles.flat());
      geometry.computeVertexNormals();
      this.world.add(new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({color: 0x30a0c0, transparent: true, opacity: 0.3,
                                                                              side: THREE.DoubleSide, depthWrite: false})));
    }
    if (scene.ghost) {
      const group = new THREE.Group();
      this.world.add(group);
      new Drawing(THREE, scene, group, 0.35).draw(scene.ghost, scene.joints);
    }
    const legend = this.root.querySelector(".kingen-legend");
    legend.innerHTML = Object.entries(STATUS_WORDS).map(([key, words]) =>
      `<span><i style="background:#${STATUS_COLOURS[key].toString(16).padStart(6, "0")}"></i>${words}</span>`).join("")
      + (scene.ghost ? `<span><i style="background:#9ab;opacity:.5"></i>${scene.ghost.label || "ghost"}`
                       + (scene.ghost.scale ? ` (changes shown ×${scene.ghost.scale})` : "") + "</span>" : "")
      + (scene.surface ? `<span><i style="background:#30a0c0;opacity:.4"></i>${scene.surface.label || "surface"}</span>` : "");
    this.setUpTimeline();
  }

  setUpTimeline() {
    const frames = this.scene.frames || [], box = this.root.querySelector(".kingen-timeline");
    if (!frames.length) { box.hidden = true; return; }
    const slider = box.querySelector("input"), play = box.querySelector("button"), marks = box.querySelector(".kingen-marks");
    slider.max = frames.length - 1;
    slider.value = 0;
    slider.addEventListener("input", () => this.showFrame(Number(slider.value)));
    let timer = null;
    play.addEventListener("click", () => {
      if (timer) { clearInterval(timer); timer = null; play.textContent = "play"; return; }
      play.textContent = "pause";
      timer = setInterval(() => {
        const next = (Number(slider.value) + 1) % frames.length;
        slider.value = next;
        this.showFrame(next);
      }, 40);
    });
    // One button per place of the path (the markers' frames' t): several problems at one place
    // share it, numbered "1-6" (or "2,5"); the labels in full on hover and beside the slider there.
    const places = new Map();
    (this.scene.markers || []).forEach((marker, n) => {
      const t = frames[marker.frame].t;
      places.set(t, [...(places.get(t) || []), [marker, n]]);
    });
    for (const group of places.values()) {
      const numbers = group.map(([, n]) => n + 1), frame = group[0][0].frame;
      const button = marks.appendChild(document.createElement("button"));
      button.className = "kingen-marker";
      button.textContent = numbers.length === 1 ? String(numbers[0])
        : numbers.every((v, i) => i === 0 || v === numbers[i - 1] + 1) ? `${numbers[0]}-${numbers.at(-1)}` : numbers.join(",");
      button.title = group.map(([marker, n]) => `${n + 1}: ${marker.label}`).join("\n");
      button.style.left = `${100 * frame / Math.max(1, frames.length - 1)}%`;
      button.addEventListener("click", () => { slider.value = frame; this.showFrame(frame); });
    }
    if (Number.isInteger(this.scene.start_frame)) slider.value = this.scene.start_frame;  // startView shows it
    else box.querySelector(".kingen-frame").textContent = `as it opened; move the slider to see the ${frames.length} frames`;
  }

  showFrame(index) {
    const frame = this.scene.frames[index];
    const marked = (this.scene.markers || []).map((marker, n) => [marker, n])
      .filter(([marker]) => this.scene.frames[marker.frame].t === frame.t);  // every problem at this place
    this.root.querySelector(".kingen-frame").textContent = [frame.label ?? `t = ${Number(frame.t).toFixed(3)} s`,
      ...marked.map(([marker, n]) => `${n + 1}: ${marker.label}`)].join("; ");
    if (this.routine) { this.setPose(frame.pose, frame.posture ?? this.posture); return; }
    this.pose = frame.pose.slice();
    this.show(frame.joints, frame.warning, "kingen");
  }

  // The machine moved to these joints (mm, radians) on the page's posture: the pose the routine's
  // forward kinematics finds from the page's pose, then answered as any pose; a note where none.
  jog(joints) {
    const found = this.routine.forward(joints, this.posture, this.pose);
    const note = this.root.querySelector(".kingen-note");
    if (found.status !== 0) {
      note.textContent = `No pose found for these joints in posture ${this.posture}: ${FORWARD_WORDS[found.status] || `status ${found.status}`}.`;
      return;
    }
    this.setPose(found.pose, this.posture);
  }

  change(k, value) {
    this.pose[k] = value;
    this.update();
  }

  setPose(pose, posture) {
    this.pose = pose.slice();
    if (posture !== undefined) this.posture = posture;
    this.scene.coordinates.forEach((name, k) => { for (const field of this.fields[name]) field.value = Number(this.pose[k].toFixed(6)); });
    this.root.querySelector(".kingen-posture").value = String(this.posture);
    this.update();
  }

  // The routine's answer at the page's pose and posture, drawn, written and timed.
  update() {
    if (!this.routine) return;
    const started = performance.now();
    if (this.scene.free.length < 6) {
      const machine = this.routine.machinePose(this.pose);
      if (machine && machine.pose) this.pose = machine.pose;
      this.scene.coordinates.forEach((name, k) => {
        if (!this.scene.free.includes(name)) for (const field of this.fields[name]) field.value = Number(this.pose[k].toFixed(6));
      });
    }
    const answer = this.routine.inverse(this.pose, this.posture);
    this.routineTimes.push(performance.now() - started);
    this.show(answer.joints, answer.warning, "wasm");
    const spent = performance.now() - started;
    this.times.push(spent);
    const timing = document.getElementById("kingen-timing");
    if (timing) {
      // The first answer is the page's at load (its shaders compiled then); the changes are the rest.
      const quantile = (list, q) => list.length ? list.slice().sort((a, b) => a - b)[Math.floor(q * (list.length - 1))] : null;
      const changes = this.times.slice(1), routine = this.routineTimes.slice(1);
      timing.textContent = JSON.stringify({load_ms: this.times[0], changes: changes.length, median_ms: quantile(changes, 0.5),
                                           p95_ms: quantile(changes, 0.95), max_ms: quantile(changes, 1),
                                           over_50_ms: changes.filter(spent => spent > 50).length,
                                           routine_median_ms: quantile(routine, 0.5), routine_max_ms: quantile(routine, 1)});
    }
  }

  show(joints, warning, by) {
    this.joints = joints;
    this.warning = warning;
    this.drawn = drawingAt(this.scene, this.pose, joints, warning, this.drawn);
    this.machine.draw(this.drawn, joints);
    const out = document.getElementById("kingen-joints");
    if (out && this.root.dataset.primary === "1") {
      out.textContent = JSON.stringify({joints, warning, by, pose: this.pose, posture: this.posture,
                                        ...(this.addressWarning ? {address_warning: this.addressWarning} : {})});
    }
    const drawn = document.getElementById("kingen-drawing");
    if (drawn && this.root.dataset.primary === "1") drawn.textContent = JSON.stringify(this.drawn);
    if (!this.rows) this.rows = joints.map((_, i) => this.tableRow(i));
    joints.forEach((q, i) => {
      const status = i < this.drawn.limbs.length ? this.drawn.limbs[i].status : wristStatus(this.scene, i, q);
      const [row, value, words, gauge] = this.rows[i], travel = this.scene.travel[i];
      row.className = `kingen-${status}`;
      if (bothEnds(travel)) {
        const shown = this.scene.joint_units[i] === "rad" ? q / DEG : q;
        gauge.firstChild.style.left = `${100 * Math.max(0, Math.min(1, (shown - travel[0]) / (travel[1] - travel[0])))}%`;
      }
      if (value.tagName === "INPUT") value.value = valueDigits(this.scene, i, q);
      else value.textContent = valueText(this.scene, i, q);
      words.textContent = STATUS_WORDS[status];
    });
    this.root.querySelector(".kingen-warning").textContent = `posture ${this.posture}: ${warning}`;
    this.render();
  }

  // Joint i's row of the table, made once: [row, its value (a field where the routine can move
  // the joint there: forward kinematics from the pose shown), its status].
  tableRow(i) {
    const row = this.root.querySelector(".kingen-table tbody").insertRow(), deg = this.scene.joint_units[i] === "rad";
    row.insertCell().textContent = this.scene.joint_names[i];
    const cell = row.insertCell();
    let value = cell;
    if (this.routine) {
      value = Object.assign(document.createElement("input"), {type: "number", step: "any", className: "kingen-joint"});
      value.title = `${this.scene.joint_names[i]} in ${deg ? "degrees" : "mm"}: type a value to move the joint`;
      value.addEventListener("change", () => {
        if (value.value === "" || !Number.isFinite(Number(value.value))) { value.value = valueDigits(this.scene, i, this.joints[i]); return; }
        const joints = this.joints.slice();
        joints[i] = Number(value.value) * (deg ? DEG : 1);
        this.jog(joints);
      });
      cell.append(value, deg ? "°" : " mm");
    }
    const travel = row.insertCell(), gauge = document.createElement("span");
    travel.textContent = travelText(this.scene, i);
    if (bothEnds(this.scene.travel[i])) {  // where the joint is in its travel: a mark on a bar, as a jog dialog shows it
      gauge.className = "kingen-gauge";
      gauge.append(document.createElement("i"));
      travel.append(gauge);
    }
    return [row, value, row.insertCell(), gauge];
  }

  render() {
    const {orbit, camera} = this, ce = Math.cos(orbit.elevation);
    camera.position.set(orbit.target[0] + orbit.distance * ce * Math.cos(orbit.azimuth),
                        orbit.target[1] + orbit.distance * ce * Math.sin(orbit.azimuth),
                        orbit.target[2] + orbit.distance * Math.sin(orbit.elevation));
    camera.lookAt(...orbit.target);
    this.renderer.render(this.world, camera);
    const canvas = this.renderer.domElement, {THREE} = this;
    const place = (div, p) => {
      const v = new THREE.Vector3(...p).project(camera);
      div.style.left = `${(v.x + 1) / 2 * canvas.clientWidth}px`;
      div.style.top = `${(1 - v.y) / 2 * canvas.clientHeight}px`;
    };
    this.labels.forEach((div, i) => {
      div.className = "kingen-label";
      if (i < this.drawn.limbs.length) {
        const limb = this.drawn.limbs[i];
        place(div, scaled(add(limb.base_side, limb.platform_point), 0.5));
      } else if (this.drawn.tool) {
        const h = this.drawn.platform;
        place(div, add([h[0][3], h[1][3], h[2][3]], [0, 0, this.scene.size * 0.06 * (i - this.drawn.limbs.length + 1)]));
      }
      div.textContent = `${this.scene.joint_names[i]} ${valueText(this.scene, i, this.joints[i])}`
        + (this.scene.travel[i] ? ` [${this.scene.travel[i][0] ?? "-∞"}, ${this.scene.travel[i][1] ?? "∞"}]` : "");
    });
    for (const [position, div] of this.extraLabels) place(div, position);
    this.unclutter();
  }

  // A label that would cover one before it is hidden (the table and the timeline hold every
  // value): the overlays' labels (a report's findings) first, then the joints'. The boxes are all
  // read in one layout, then the hidden ones hidden.
  unclutter() {
    const divs = [...this.extraLabels.map(([, div]) => div), ...this.labels];
    divs.forEach(div => { div.style.visibility = ""; });
    const boxes = divs.map(div => div.getBoundingClientRect()), kept = [];
    const covers = (a, b) => a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom;
    boxes.forEach((box, i) => {
      if (box.width && kept.some(other => covers(box, other))) divs[i].style.visibility = "hidden";
      else kept.push(box);
    });
  }
}

function wristStatus(scene, index, q) {
  return beyondTravel(scene, index, q) ? "limits" : "good";
}

// #bench=N: N changes of the first free coordinate's slider, each an input event as a user's
// drag makes, answered and timed by update() into #kingen-timing (benchmarks/view.py reads it).
function bench(view, count) {
  const name = view.scene.free[0], k = view.scene.coordinates.indexOf(name), slider = view.fields[name][0];
  const home = view.scene.region.home[k], range = view.scene.region.range[k];
  for (let i = 0; i < count; i++) {
    slider.value = home + range * Math.sin(i);
    slider.dispatchEvent(new Event("input"));
  }
}

async function startView(root) {
  const scene = JSON.parse(root.querySelector(".kingen-scene").textContent);
  const THREE = await loadThree();
  if (window.kingenRoutineReady) await window.kingenRoutineReady;
  const view = new View(root, scene, THREE);
  const asked = root.dataset.primary === "1" ? parseFragment(window.location.hash, scene) : {problems: []};
  if (asked.problems.length) {  // said in the note and in #kingen-joints (show() writes it there)
    view.addressWarning = `The address is not read in full: ${asked.problems.join("; ")}.`;
    view.root.querySelector(".kingen-note").textContent += ` ${view.addressWarning}`;
  }
  if (asked.joints && view.routine) {
    if (asked.posture !== undefined) view.posture = asked.posture;
    view.jog(asked.joints);
  } else if (asked.pose || asked.joints || asked.posture !== undefined) {
    if (view.routine) view.setPose(asked.pose || view.pose, asked.posture ?? view.posture);
    else view.root.querySelector(".kingen-note").textContent += " The pose in the address is not drawn: it needs the routine.";
  } else if (Number.isInteger(scene.start_frame) && (scene.frames || [])[scene.start_frame]) {
    view.showFrame(scene.start_frame);  // a report opens at a frame of its own (check-path: its first problem)
  } else if (view.routine) {
    view.update();
  } else {
    view.show(scene.joints, scene.warning, "kingen");
  }
  if (asked.bench && view.routine) bench(view, asked.bench);
  root.dataset.ready = "1";
  window.kingenView = view;
  return view;
}

document.querySelectorAll(".kingen-view").forEach(root => startView(root).catch(error => {
  root.querySelector(".kingen-note").textContent = `The view could not start: ${error}`;
  const out = document.getElementById("kingen-joints");
  if (out) out.textContent = JSON.stringify({error: String(error)});
}));
