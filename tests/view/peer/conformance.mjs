// The live view (docs/view.md) seen by the official Foxglove WebSocket client.
//
//   node conformance.mjs --url ws://127.0.0.1:PORT/ --modules DIR [--map MAP.yaml]
//                        [--duration S] [--timeout S]
//
// DIR holds node_modules with the packages of package-lock.json (run_view_peer.py installs
// them). FoxgloveClient (@foxglove/ws-protocol) over a `ws` WebSocket connects, and this
// script checks:
//   - serverInfo comes first: name "sen3bot", no capabilities at all (none that accepts input:
//     clientPublish, parameters, services, connection graph, assets);
//   - one advertise of every documented channel: encoding json, schemaEncoding jsonschema, the
//     documented schemaName, a schema that is JSON and compiles as JSON Schema (ajv);
//   - every message of every channel, for at least --duration seconds and until each channel
//     has two messages (/camera/image may be absent): UTF-8 JSON valid against the advertised
//     schema and, for foxglove.* schemas, against the official one of @foxglove/schemas, its
//     bytes fields base64 as the json encoding requires;
//   - what the messages mean: /tf carries map->odom, odom->base_link, base_link->laser (unit
//     planar rotations, a fixed laser mount) and composes to /mission's pose; grids hold
//     column_count * rows one-byte cells, and /map is the map file of --map (its size, cell
//     size, origin and trinary cells, row 0 the lowest y); /scan's ranges are the LMS200's readings from start to
//     end at one of its angular resolutions; timestamps never go back per channel (strictly
//     forward per /tf child frame and on the periodic channels); the rates of the fast channels
//     are near their documented periods;
//   - unsubscribe stops a channel while the others go on, a new subscription resumes it, a
//     new subscription to /map gets the map at once.
// Prints a table per channel (messages, bytes, rate) and exits 0 when every check passed, 1
// otherwise.
import { createRequire } from "node:module";
import fs from "node:fs";
import path from "node:path";
import { parseArgs } from "node:util";

const { values: opts } = parseArgs({
  options: {
    url: { type: "string" },
    modules: { type: "string" },
    map: { type: "string" },
    duration: { type: "string", default: "20" },
    timeout: { type: "string", default: "90" },
  },
});
if (!opts.url || !opts.modules) {
  console.error("usage: node conformance.mjs --url ws://HOST:PORT/ --modules DIR [--duration S] [--timeout S]");
  process.exit(2);
}
const require = createRequire(path.join(path.resolve(opts.modules), "package.json"));
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");
const Ajv = require("ajv");
const Ajv2019 = require("ajv/dist/2019");
const Ajv2020 = require("ajv/dist/2020");
const addFormats = require("ajv-formats");
const official = require("@foxglove/schemas/jsonschema");

const DURATION_MS = Number(opts.duration) * 1000;
const TIMEOUT_MS = Number(opts.timeout) * 1000;

// The documented channels: schema, period (s), whether the channel may be missing.
const DOCUMENTED = {
  "/map": { schema: "foxglove.Grid", period: 5 },
  "/costmap/global": { schema: "foxglove.Grid", period: 2 },
  "/costmap/local": { schema: "foxglove.Grid", period: 0.5 },
  "/scan": { schema: "foxglove.LaserScan", period: 0.2 },
  "/tf": { schema: "foxglove.FrameTransform", period: 0.1, perPeriod: 3 },
  "/plan": { schema: "foxglove.PosesInFrame", period: 1 },
  "/safe_path": { schema: "foxglove.SceneUpdate", period: 2 },
  "/path/driven": { schema: "foxglove.PosesInFrame", period: 1 },
  "/dwa": { schema: "foxglove.PosesInFrame", period: 0.2 },
  "/people": { schema: "foxglove.SceneUpdate", period: 0.2 },
  "/camera/image": { schema: "foxglove.CompressedImage", period: 1, optional: true },
  "/stats": { schema: "sen3bot.TaskStats", period: 1 },
  "/mission": { schema: "sen3bot.Mission", period: 0.5 },
};
const INPUT_CAPABILITIES = ["clientPublish", "parameters", "parametersSubscribe", "services", "connectionGraph", "assets"];
const TF_EDGES = ["map>odom", "odom>base_link", "base_link>laser"];
const LMS200_RESOLUTIONS_DEG = [0.25, 0.5, 1.0];

const failures = [];
const notes = [];
const failureCounts = new Map();
function fail(message) {
  // The same defect on every message is reported a few times, then counted.
  const key = message.replace(/-?\d+(\.\d+)?(e[+-]?\d+)?/g, "#");
  const n = (failureCounts.get(key) ?? 0) + 1;
  failureCounts.set(key, n);
  if (n <= 3) {
    failures.push(message);
    console.error(`FAIL ${message}`);
  }
}
function note(message) {
  notes.push(message);
  console.error(`note ${message}`);
}
const log = (message) => console.error(`conformance: ${message}`);

// --- JSON Schema ------------------------------------------------------------------------------

function base64Keyword(ajv) {
  // Foxglove's json encoding carries bytes fields as base64 strings; ajv treats contentEncoding
  // as an annotation, so it becomes an assertion here.
  ajv.removeKeyword("contentEncoding");
  ajv.addKeyword({
    keyword: "contentEncoding",
    schemaType: "string",
    errors: true,
    validate: function check(encoding, data) {
      if (encoding !== "base64" || typeof data !== "string") return true;
      const ok = data.length % 4 === 0 && /^[A-Za-z0-9+/]*={0,2}$/.test(data);
      if (!ok) check.errors = [{ keyword: "contentEncoding", message: "is not base64", params: {} }];
      return ok;
    },
  });
  return ajv;
}
function ajvFor(schema) {
  const dialect = typeof schema?.$schema === "string" ? schema.$schema : "";
  const Class = dialect.includes("2020-12") ? Ajv2020 : dialect.includes("2019-09") ? Ajv2019 : Ajv;
  const ajv = new Class({ strict: false, allErrors: true, validateFormats: true });
  addFormats(ajv);
  return base64Keyword(ajv);
}
function describeErrors(errors) {
  return (errors ?? []).slice(0, 3).map((e) => `${e.instancePath || "/"} ${e.message}`).join("; ");
}
const officialValidators = new Map();
function officialValidator(schemaName) {
  if (!schemaName.startsWith("foxglove.")) return null;
  if (!officialValidators.has(schemaName)) {
    const schema = official[schemaName.slice("foxglove.".length)];
    officialValidators.set(schemaName, schema ? ajvFor(schema).compile(schema) : undefined);
  }
  return officialValidators.get(schemaName);
}

// --- State ------------------------------------------------------------------------------------

const channels = new Map(); // id -> channel
const byTopic = new Map(); // topic -> channel
const subscriptions = new Map(); // subscription id -> channel
const stats = new Map(); // topic -> {count, bytes, first, last, ...}
const order = []; // the first server messages' kinds
let serverInfo = null;
let advertiseCount = 0;
let closed = null;

function statsOf(topic) {
  if (!stats.has(topic)) {
    stats.set(topic, { count: 0, bytes: 0, first: 0, last: 0, lastByChild: new Map(),
                       resubscribedAt: 0, sinceResubscribe: 0, firstAfterResubscribe: null });
  }
  return stats.get(topic);
}

// --- The map file: a ROS map_server YAML and its binary PGM -----------------------------------

function loadMap(file) {
  const yaml = fs.readFileSync(file, "utf8");
  const value = (key) => yaml.match(new RegExp(`^${key}:\\s*(.+?)\\s*(#.*)?$`, "m"))?.[1];
  const image = value("image");
  const resolution = Number(value("resolution"));
  const origin = (value("origin") ?? "").replace(/[[\]]/g, "").split(",").map(Number);
  const negate = Number(value("negate") ?? 0);
  const occupied = Number(value("occupied_thresh") ?? 0.65);
  const free = Number(value("free_thresh") ?? 0.196);
  if (!image || !(resolution > 0) || origin.length < 2) throw new Error(`${file}: not a map YAML`);
  const pgm = fs.readFileSync(path.resolve(path.dirname(file), image));
  // P5, then width, height and maxval, each after white space and comments.
  const fields = [];
  let i = 2;
  while (fields.length < 3) {
    while (/\s/.test(String.fromCharCode(pgm[i]))) i++;
    if (pgm[i] === 0x23) { while (pgm[i] !== 0x0a) i++; continue; }
    let token = "";
    while (!/\s/.test(String.fromCharCode(pgm[i]))) token += String.fromCharCode(pgm[i++]);
    fields.push(Number(token));
  }
  i += 1;
  if (pgm.subarray(0, 2).toString() !== "P5" || fields[2] > 255) throw new Error(`${file}: ${image} is not an 8-bit binary PGM`);
  const [width, height, maxval] = fields;
  const cells = Buffer.alloc(width * height);
  for (let row = 0; row < height; row++) {
    for (let col = 0; col < width; col++) {
      const v = pgm[i + (height - 1 - row) * width + col];  // PGM row 0 is the top
      const p = negate ? v / maxval : (maxval - v) / maxval;
      cells[row * width + col] = p > occupied ? 100 : p < free ? 0 : 255;
    }
  }
  return { file, width, height, resolution, origin, cells };
}
const mapFile = opts.map ? loadMap(opts.map) : null;
let mapCompared = false;

function compareMap(m, data) {
  const f = mapFile;
  const rows = data.length / m.column_count;
  if (m.column_count !== f.width || rows !== f.height) {
    return fail(`/map: ${m.column_count} x ${rows} cells, ${path.basename(f.file)} has ${f.width} x ${f.height}`);
  }
  if (Math.abs(m.cell_size.x - f.resolution) > 1e-9) fail(`/map: cell size ${m.cell_size.x} m, the map's resolution ${f.resolution}`);
  const o = m.pose.position;
  if (Math.abs(o.x - f.origin[0]) > 1e-6 || Math.abs(o.y - f.origin[1]) > 1e-6) {
    fail(`/map: origin (${o.x}, ${o.y}), the map's (${f.origin[0]}, ${f.origin[1]})`);
  }
  let differ = 0, first = -1;
  for (let k = 0; k < data.length; k++) {
    if (data[k] !== f.cells[k]) {
      differ++;
      if (first < 0) first = k;
    }
  }
  // The firmware's own thresholds may round a few grey cells the other way; a flipped or
  // shifted map differs in thousands.
  if (differ > data.length / 200) {
    const r = Math.floor(first / f.width), c = first % f.width;
    fail(`/map: ${differ} of ${data.length} cells differ from ${path.basename(f.file)} (the first at column ${c}, row ${r}: ${data[first]}, the file's ${f.cells[first]})`);
  }
  if (!mapCompared) log(`/map against ${path.basename(f.file)}: ${f.width} x ${f.height} cells, ${differ} differ`);
  mapCompared = true;
}

// --- Meaning checks per schema ------------------------------------------------------------------

const finite = (...xs) => xs.every((x) => typeof x === "number" && Number.isFinite(x));
const stampNs = (t) => BigInt(t.sec) * 1000000000n + BigInt(t.nsec);
function checkQuaternion(topic, q, planar) {
  if (!finite(q.x, q.y, q.z, q.w)) return fail(`${topic}: a quaternion that is not finite`);
  const norm = Math.hypot(q.x, q.y, q.z, q.w);
  if (Math.abs(norm - 1) > 1e-6) fail(`${topic}: a quaternion of norm ${norm}, not 1`);
  if (planar && (Math.abs(q.x) > 1e-9 || Math.abs(q.y) > 1e-9)) fail(`${topic}: a rotation out of the plane (x ${q.x}, y ${q.y})`);
}
const yaw = (q) => 2 * Math.atan2(q.z, q.w);
const wrap = (a) => Math.atan2(Math.sin(a), Math.cos(a));

const tfHistory = { "map>odom": [], "odom>base_link": [] }; // [stamp ns, x, y, theta]
let laserMount = null;
const missions = [];
let lastStats = null;
let statsSeen = 0;

function checkGrid(topic, m) {
  const field = topic === "/map" ? "occupancy" : "cost";
  if (m.frame_id !== "map") fail(`${topic}: frame_id "${m.frame_id}", not "map"`);
  if (!(m.column_count > 0)) return fail(`${topic}: column_count ${m.column_count}`);
  if (m.cell_stride !== 1 || m.row_stride !== m.column_count) {
    fail(`${topic}: cell_stride ${m.cell_stride}, row_stride ${m.row_stride} for one uint8 per cell and ${m.column_count} columns`);
  }
  if (m.fields?.length !== 1 || m.fields[0].name !== field || m.fields[0].offset !== 0 || m.fields[0].type !== 1) {
    fail(`${topic}: fields ${JSON.stringify(m.fields)}, not one UINT8 "${field}" at offset 0`);
  }
  if (!(m.cell_size?.x > 0) || Math.abs(m.cell_size.x - m.cell_size.y) > 1e-9) fail(`${topic}: cell_size ${JSON.stringify(m.cell_size)}`);
  checkQuaternion(topic, m.pose.orientation, true);
  const data = Buffer.from(m.data, "base64");
  const rows = Math.floor(data.length / m.column_count);
  if (rows < 1 || rows * m.column_count !== data.length) {
    fail(`${topic}: ${data.length} bytes of cells are not column_count ${m.column_count} * a whole number of rows`);
  }
  if (topic === "/map") {
    const odd = data.findIndex((v) => v !== 0 && v !== 100 && v !== 255);
    if (odd >= 0) fail(`/map: cell ${odd} is ${data[odd]}, not 0, 100 or 255`);
    if (!data.includes(100)) fail("/map: no occupied cell");
    if (mapFile && rows * m.column_count === data.length) compareMap(m, data);
  }
  return { columns: m.column_count, rows };
}

function checkScan(m) {
  if (m.frame_id !== "laser") fail(`/scan: frame_id "${m.frame_id}", not "laser"`);
  const n = m.ranges.length;
  if (n < 2) return fail(`/scan: ${n} ranges`);
  if (m.intensities.length !== 0 && m.intensities.length !== n) fail(`/scan: ${m.intensities.length} intensities for ${n} ranges`);
  if (!(m.end_angle > m.start_angle)) return fail(`/scan: end_angle ${m.end_angle} not after start_angle ${m.start_angle}`);
  // Readings are equally spaced from start_angle to end_angle, both included: the count is
  // (end - start) / increment + 1 for one of the LMS200's angular resolutions.
  const span = m.end_angle - m.start_angle;
  const matches = LMS200_RESOLUTIONS_DEG.filter((deg) => {
    const increment = (deg * Math.PI) / 180;
    return Math.abs(span / increment + 1 - n) < 1e-3;
  });
  if (matches.length === 0) {
    fail(`/scan: ${n} ranges over ${(span * 180 / Math.PI).toFixed(4)} deg: no LMS200 increment (0.25, 0.5, 1 deg) gives (end-start)/increment + 1 = ${n}`);
  }
  const bad = m.ranges.findIndex((r) => !finite(r) || r < 0 || r > 81.92);
  if (bad >= 0) fail(`/scan: range ${bad} is ${m.ranges[bad]}`);
  if (!m.ranges.some((r) => r > 0)) fail("/scan: every reading is \"no return\"");
}

function checkTf(m) {
  const edge = `${m.parent_frame_id}>${m.child_frame_id}`;
  if (!TF_EDGES.includes(edge)) return fail(`/tf: unexpected transform ${m.parent_frame_id} -> ${m.child_frame_id}`);
  checkQuaternion("/tf", m.rotation, true);
  if (!finite(m.translation.x, m.translation.y, m.translation.z) || m.translation.z !== 0) {
    fail(`/tf: ${edge} translation ${JSON.stringify(m.translation)}`);
  }
  const pose = [stampNs(m.timestamp), m.translation.x, m.translation.y, yaw(m.rotation)];
  if (edge === "base_link>laser") {
    if (laserMount === null) laserMount = pose;
    else if (Math.abs(pose[1] - laserMount[1]) > 1e-9 || Math.abs(pose[2] - laserMount[2]) > 1e-9 || Math.abs(wrap(pose[3] - laserMount[3])) > 1e-9) {
      fail(`/tf: the laser mount moved: ${pose.slice(1)} after ${laserMount.slice(1)}`);
    }
  } else {
    tfHistory[edge].push(pose);
  }
  return edge;
}

function checkPoses(topic, m) {
  if (m.frame_id !== "map") fail(`${topic}: frame_id "${m.frame_id}", not "map"`);
  for (const p of m.poses) {
    if (!finite(p.position.x, p.position.y, p.position.z)) fail(`${topic}: a pose that is not finite`);
    checkQuaternion(topic, p.orientation, true);
  }
  if (topic === "/path/driven") {
    if (m.poses.length > 512) fail(`/path/driven: ${m.poses.length} poses, more than the newest 512`);
    for (let i = 1; i < m.poses.length; i++) {
      const a = m.poses[i - 1].position, b = m.poses[i].position;
      const d = Math.hypot(b.x - a.x, b.y - a.y);
      if (d < 0.05 || d > 1.0) {
        fail(`/path/driven: poses ${i - 1} and ${i} are ${d.toFixed(3)} m apart (one per 0.1 m)`);
        break;
      }
    }
  }
}

function checkScene(topic, m) {
  const ids = m.entities.map((e) => e.id);
  if (topic === "/safe_path") {
    // Before the first plan of a case the waypoints may have no line yet; once drawn, the safe
    // curve's zero set is a line list (segments: an even count of points) and the waypoints a
    // strip (checked to have come at the end).
    for (const e of m.entities) {
      const want = e.id === "safe_curve" ? 2 : e.id === "waypoints" ? 0 : null;
      if (want === null) fail(`/safe_path: entity "${e.id}"`);
      else if (e.lines.some((l) => l.type !== want)) fail(`/safe_path: ${e.id} with a line of type ${e.lines.map((l) => l.type)}, not ${want === 2 ? "a list (2)" : "a strip (0)"}`);
      else if (want === 2 && e.lines.some((l) => l.points.length % 2 !== 0)) fail(`/safe_path: safe_curve with an odd count of segment ends`);
      else if (e.lines.some((l) => l.points.length >= 2)) sceneSeen.add(e.id);
    }
  } else {
    if (m.deletions.length < 1 || m.deletions[0].type !== 1) fail(`/people: does not start with a delete-all (${JSON.stringify(m.deletions)})`);
    for (const e of m.entities) {
      if (!/^(person|mover)\/\S+$/.test(e.id)) fail(`/people: entity id "${e.id}"`);
      // A velocity arrow only for one that moves (over 5 cm/s).
      if (e.cylinders.length < 1 || e.arrows.length > 1) fail(`/people: entity ${e.id} without its cylinder, or with more than one arrow`);
      if (e.id.startsWith("person/") && (e.texts.length < 1 || !e.lines.some((l) => l.type === 1))) {
        fail(`/people: ${e.id} without its label and cage (line loop)`);
      }
    }
  }
  for (const e of m.entities) if (e.frame_id !== "map") fail(`${topic}: entity ${e.id} in frame "${e.frame_id}"`);
}

const sceneSeen = new Set(); // /safe_path entities drawn at least once

function checkImage(m) {
  if (m.format !== "jpeg") fail(`/camera/image: format "${m.format}", not "jpeg"`);
  const data = Buffer.from(m.data, "base64");
  if (data.length < 4 || data[0] !== 0xff || data[1] !== 0xd8 || data.at(-2) !== 0xff || data.at(-1) !== 0xd9) {
    fail(`/camera/image: ${data.length} bytes that are not one JPEG (SOI ... EOI)`);
  }
}

function checkStats(m) {
  const keys = ["name", "thread", "period_us", "budget_us", "runs", "overruns", "slips", "skips", "exec_mean_us",
                "exec_max_us", "cpu_mean_us", "cpu_max_us", "jitter_p99_us"];
  if (!Array.isArray(m.tasks) || m.tasks.length === 0) return fail("/stats: no tasks");
  for (const t of m.tasks) {
    const missing = keys.filter((k) => !(k in t));
    if (missing.length) fail(`/stats: task ${t.name} without ${missing}`);
  }
  // The first /stats may have been counted before this client was.
  statsSeen += 1;
  if (statsSeen > 1 && !(m.view?.clients >= 1)) fail(`/stats: view.clients ${m.view?.clients} while this client is connected`);
  if (lastStats) {
    // A simulated run starts each case's firmware afresh: its uptime and task counters too.
    const runs = new Map(lastStats.tasks.map((t) => [t.name, t.runs]));
    const restarted = m.tasks.every((t) => runs.has(t.name) && t.runs < runs.get(t.name));
    if (m.uptime_s < lastStats.uptime_s && !restarted) fail(`/stats: uptime_s went back from ${lastStats.uptime_s} to ${m.uptime_s}, the tasks' runs did not`);
    if (restarted) note(`/stats: the task table started again (uptime ${lastStats.uptime_s} s -> ${m.uptime_s} s): a new case`);
    if (m.view.sent < lastStats.view.sent) fail(`/stats: view.sent went back from ${lastStats.view.sent} to ${m.view.sent}`);
  }
  lastStats = m;
}

function checkMission(m) {
  const keys = ["timestamp", "state", "goals_reached", "goals_total", "goal", "pose", "localized", "lost", "v", "w", "controller", "safety"];
  const missing = keys.filter((k) => !(k in m));
  if (missing.length) return fail(`/mission: without ${missing}`);
  if (typeof m.state !== "string" || !m.state) fail(`/mission: state ${JSON.stringify(m.state)}`);
  if (!(m.goals_reached >= 0 && m.goals_reached <= m.goals_total)) fail(`/mission: goals ${m.goals_reached} of ${m.goals_total}`);
  if (!finite(m.pose?.x, m.pose?.y, m.pose?.theta)) fail(`/mission: pose ${JSON.stringify(m.pose)}`);
  if (!Array.isArray(m.safety)) fail("/mission: safety is not a list");
  if (m.localized) missions.push([stampNs(m.timestamp), m.pose.x, m.pose.y, m.pose.theta]);
}

// --- The client -------------------------------------------------------------------------------

const validators = new Map(); // channel id -> {advertised, official}
let checksStarted = false;

function onAdvertise(list) {
  advertiseCount += 1;
  order.push("advertise");
  if (advertiseCount > 1) note(`advertise number ${advertiseCount} (${list.map((c) => c.topic)}): the documented protocol sends one`);
  for (const c of list) {
    if (channels.has(c.id)) fail(`channel id ${c.id} advertised twice`);
    if (byTopic.has(c.topic)) fail(`topic ${c.topic} advertised twice`);
    channels.set(c.id, c);
    byTopic.set(c.topic, c);
    const documented = DOCUMENTED[c.topic];
    if (!documented) fail(`${c.topic}: an undocumented channel`);
    else if (c.schemaName !== documented.schema) fail(`${c.topic}: schemaName "${c.schemaName}", documented ${documented.schema}`);
    if (c.encoding !== "json") fail(`${c.topic}: encoding "${c.encoding}", not json`);
    if (c.schemaEncoding !== "jsonschema") fail(`${c.topic}: schemaEncoding "${c.schemaEncoding}", not jsonschema`);
    if (typeof c.schemaName !== "string" || !c.schemaName) fail(`${c.topic}: no schemaName`);
    let schema;
    try {
      schema = JSON.parse(c.schema);
    } catch (error) {
      fail(`${c.topic}: its schema is not JSON (${error.message})`);
      continue;
    }
    let advertised;
    try {
      advertised = ajvFor(schema).compile(schema);
    } catch (error) {
      fail(`${c.topic}: its schema is not valid JSON Schema (${error.message})`);
      continue;
    }
    const fox = officialValidator(c.schemaName ?? "");
    if (fox === undefined) fail(`${c.topic}: ${c.schemaName} is not one of @foxglove/schemas`);
    validators.set(c.id, { advertised, official: fox ?? null });
  }
  for (const [topic, d] of Object.entries(DOCUMENTED)) {
    if (!d.optional && !byTopic.has(topic) && advertiseCount === 1) fail(`${topic}: not advertised`);
  }
}

function onMessage(event) {
  const now = Date.now();
  const channel = subscriptions.get(event.subscriptionId);
  if (!channel) return fail(`a message for subscription ${event.subscriptionId}, which is not one of this client's`);
  const topic = channel.topic;
  const s = statsOf(topic);
  const bytes = event.data.byteLength;
  s.count += 1;
  s.bytes += bytes;
  if (!s.first) s.first = now;
  s.last = now;
  if (s.firstAfterResubscribe === null && s.resubscribedAt) s.firstAfterResubscribe = now - s.resubscribedAt;
  if (s.resubscribedAt) s.sinceResubscribe += 1;

  let message;
  try {
    const text = new TextDecoder("utf-8", { fatal: true }).decode(event.data);
    message = JSON.parse(text);
  } catch (error) {
    return fail(`${topic}: a message that is not UTF-8 JSON (${error.message})`);
  }
  const v = validators.get(channel.id);
  if (v && !v.advertised(message)) fail(`${topic}: a message failing its advertised schema: ${describeErrors(v.advertised.errors)}`);
  if (v?.official && !v.official(message)) fail(`${topic}: a message failing the official ${channel.schemaName}: ${describeErrors(v.official.errors)}`);

  // Timestamps: the message header's (ns) and the payload's never go back.
  const header = event.timestamp;
  let key = topic;
  if (topic === "/tf" && message.child_frame_id) key = `/tf ${message.child_frame_id}`;
  const previous = s.lastByChild.get(key);
  // Channels that re-send a state (a plan, a costmap, the newest scan) may repeat its stamp;
  // the transforms, the statistics and the mission are new each time.
  const strict = ["/tf", "/stats", "/mission"].includes(topic);
  if (previous !== undefined) {
    if (header < previous || (strict && header === previous)) {
      fail(`${key}: header timestamp ${header} after ${previous}: not ${strict ? "increasing" : "non-decreasing"}`);
    }
  }
  s.lastByChild.set(key, header);
  if (!s.window) (s.stamps ??= []).push(header);
  if (previous !== undefined && header === previous) s.repeatedStamps = (s.repeatedStamps ?? 0) + 1;
  if (message.timestamp && finite(message.timestamp.sec, message.timestamp.nsec)) {
    const payload = stampNs(message.timestamp);
    if (payload !== header) s.stampDiffers = (s.stampDiffers ?? 0) + 1;
  }

  try {
    switch (channel.schemaName) {
      case "foxglove.Grid": {
        const g = checkGrid(topic, message);
        if (g) s.grid = g;
        break;
      }
      case "foxglove.LaserScan": checkScan(message); break;
      case "foxglove.FrameTransform": {
        const edge = checkTf(message);
        if (edge) (s.edges ??= new Set()).add(edge);
        break;
      }
      case "foxglove.PosesInFrame": checkPoses(topic, message); break;
      case "foxglove.SceneUpdate": checkScene(topic, message); break;
      case "foxglove.CompressedImage": checkImage(message); break;
      case "sen3bot.TaskStats": checkStats(message); break;
      case "sen3bot.Mission": checkMission(message); break;
      default: break;
    }
  } catch (error) {
    fail(`${topic}: checking a message threw ${error.message}`);
  }
}

// /mission's pose is the estimate; /tf's map->odom composed with odom->base_link must be it.
function comparePoses() {
  const composed = [];
  for (const [t, x, y, th] of tfHistory["odom>base_link"]) {
    const odom = tfHistory["map>odom"].find((p) => p[0] === t);
    if (!odom) continue;
    const [, ox, oy, oth] = odom;
    composed.push([t, ox + Math.cos(oth) * x - Math.sin(oth) * y, oy + Math.sin(oth) * x + Math.cos(oth) * y, wrap(oth + th)]);
  }
  if (composed.length === 0) return fail("/tf: no map->odom and odom->base_link of the same timestamp");
  let compared = 0, worst = 0, worstAngle = 0;
  for (const [t, x, y, th] of missions) {
    let best = null;
    for (const c of composed) if (best === null || abs(c[0] - t) < abs(best[0] - t)) best = c;
    if (abs(best[0] - t) > 150000000n) continue;
    compared += 1;
    worst = Math.max(worst, Math.hypot(best[1] - x, best[2] - y));
    worstAngle = Math.max(worstAngle, Math.abs(wrap(best[3] - th)));
  }
  if (compared === 0) return fail("/mission: no message within 0.15 s of a /tf pose: cannot compare the pose");
  log(`/tf map->base_link against /mission's pose: ${compared} compared, at most ${worst.toFixed(3)} m and ${worstAngle.toFixed(3)} rad apart`);
  if (worst > 0.2 || worstAngle > 0.2) fail(`/tf: map->base_link is up to ${worst.toFixed(3)} m and ${worstAngle.toFixed(3)} rad away from /mission's pose`);
  const first = composed[0], last = composed.at(-1);
  log(`base_link went from (${first[1].toFixed(2)}, ${first[2].toFixed(2)}) to (${last[1].toFixed(2)}, ${last[2].toFixed(2)}) m in map`);
}
const abs = (n) => (n < 0n ? -n : n);

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

function table(elapsedMs) {
  const rows = [["topic", "schema", "messages", "bytes", "rate/s", "documented/s"]];
  for (const [topic, c] of byTopic) {
    const s = statsOf(topic);
    const d = DOCUMENTED[topic];
    const rate = s.window ? s.window.count / (s.window.ms / 1000) : 0;
    rows.push([topic, c.schemaName, String(s.count), String(s.bytes), rate.toFixed(2), d ? ((d.perPeriod ?? 1) / d.period).toFixed(2) : "-"]);
  }
  const widths = rows[0].map((_, i) => Math.max(...rows.map((r) => r[i].length)));
  const lines = rows.map((r) => r.map((cell, i) => (i < 2 ? cell.padEnd(widths[i]) : cell.padStart(widths[i]))).join("  "));
  lines.splice(1, 0, widths.map((w) => "-".repeat(w)).join("  "));
  console.log(lines.join("\n"));
  console.log(`(${(elapsedMs / 1000).toFixed(1)} s of subscriptions; rates over the checked window)`);
}

async function main() {
  const started = Date.now();
  const ws = new WebSocket(opts.url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  const client = new FoxgloveClient({ ws });
  const opened = new Promise((resolve, reject) => {
    client.on("open", resolve);
    client.on("close", (event) => reject(new Error(`closed before opening (code ${event.code})`)));
  });
  client.on("error", (error) => fail(`client error: ${error?.message ?? error}`));
  client.on("close", (event) => { closed = event; });
  client.on("serverInfo", (info) => {
    order.push("serverInfo");
    if (serverInfo) fail("a second serverInfo");
    serverInfo = info;
  });
  client.on("status", (s) => {
    order.push("status");
    note(`status level ${s.level}: ${s.message}`);
  });
  client.on("advertise", onAdvertise);
  client.on("unadvertise", (ids) => fail(`unadvertise of ${ids} while the run goes on`));
  client.on("advertiseServices", () => fail("advertiseServices from a server without services"));
  client.on("parameterValues", () => fail("parameterValues from a server without parameters"));
  client.on("message", onMessage);
  client.on("time", () => order.push("time"));

  await Promise.race([opened, sleep(10000).then(() => { throw new Error("no connection within 10 s"); })]);
  if (ws.protocol !== FoxgloveClient.SUPPORTED_SUBPROTOCOL) fail(`the server chose subprotocol "${ws.protocol}"`);
  log(`connected to ${opts.url} (${ws.protocol})`);

  for (let waited = 0; (advertiseCount === 0 || !serverInfo) && waited < 5000; waited += 50) await sleep(50);
  if (!serverInfo) throw new Error("no serverInfo within 5 s");
  if (advertiseCount === 0) throw new Error("no advertise within 5 s");
  if (order[0] !== "serverInfo") fail(`the first server message is ${order[0]}, not serverInfo`);
  if (serverInfo.name !== "sen3bot") fail(`serverInfo name "${serverInfo.name}", not "sen3bot"`);
  const capabilities = serverInfo.capabilities ?? [];
  if (!Array.isArray(capabilities)) fail(`serverInfo capabilities ${JSON.stringify(capabilities)} is not a list`);
  const input = capabilities.filter((c) => INPUT_CAPABILITIES.includes(c));
  if (input.length) fail(`serverInfo capabilities that accept input: ${input}`);
  if (capabilities.length) fail(`serverInfo capabilities ${JSON.stringify(capabilities)}: the documented server has none`);
  if (serverInfo.supportedEncodings?.length) {
    note(`serverInfo supportedEncodings ${JSON.stringify(serverInfo.supportedEncodings)}: encodings for client publishing, which this server does not accept`);
  }
  log(`serverInfo ${JSON.stringify(serverInfo)}`);
  log(`advertised: ${[...byTopic.keys()].join(" ")}`);

  // Every channel, then messages for at least DURATION and until each has two.
  for (const c of channels.values()) subscriptions.set(client.subscribe(c.id), c);
  const subscribedAt = Date.now();
  const required = [...byTopic.keys()].filter((t) => !DOCUMENTED[t]?.optional);
  const enough = () => required.every((t) => statsOf(t).count >= 2);
  while ((Date.now() - subscribedAt < DURATION_MS || !enough()) && Date.now() - started < TIMEOUT_MS - 8000) {
    if (closed) throw new Error(`the server closed the connection (code ${closed.code})`);
    await sleep(100);
  }
  const windowMs = Date.now() - subscribedAt;
  for (const topic of byTopic.keys()) {
    const s = statsOf(topic);
    s.window = { count: s.count, ms: windowMs };
  }
  for (const topic of required) {
    if (statsOf(topic).count < 2) fail(`${topic}: ${statsOf(topic).count} messages in ${(windowMs / 1000).toFixed(1)} s`);
  }
  // Rates of the channels of 1 s and faster: within half and twice the documented rate (a
  // state not new since the last period may be skipped; the periods are checked below).
  for (const topic of required) {
    const d = DOCUMENTED[topic];
    if (!d || d.period > 1) continue;
    const expected = (d.perPeriod ?? 1) / d.period;
    const rate = statsOf(topic).window.count / (windowMs / 1000);
    if (rate < expected / 2 || rate > expected * 2) fail(`${topic}: ${rate.toFixed(2)} messages/s, documented ${expected.toFixed(2)}`);
  }
  // The channels new at each period: the median step between their distinct header stamps is
  // the documented period (within -20 % .. +25 %), robust to a late tick now and then.
  for (const topic of ["/tf", "/stats", "/mission"]) {
    const stamps = [...new Set(statsOf(topic).stamps ?? [])].sort((a, b) => (a < b ? -1 : a > b ? 1 : 0));
    const steps = stamps.slice(1).map((t, i) => Number(t - stamps[i]) / 1e6).sort((a, b) => a - b);
    if (steps.length < 3) continue;
    const median = steps[Math.floor(steps.length / 2)];
    const period = DOCUMENTED[topic].period * 1000;
    log(`${topic}: median step between stamps ${median.toFixed(1)} ms (documented ${period} ms), ${steps.length} steps`);
    if (median < period * 0.8 || median > period * 1.25) fail(`${topic}: the median step between its stamps is ${median.toFixed(1)} ms, the documented period ${period} ms`);
  }
  const tf = statsOf("/tf");
  for (const edge of TF_EDGES) if (!tf.edges?.has(edge)) fail(`/tf: no ${edge.replace(">", " -> ")} transform`);
  if (mapFile && !mapCompared) fail(`/map: never compared with ${mapFile.file}`);
  for (const topic of ["/map", "/costmap/global", "/costmap/local"]) {
    const g = statsOf(topic).grid;
    if (g) log(`${topic}: ${g.columns} x ${g.rows} cells`);
  }
  comparePoses();

  // Unsubscribe: /tf, /mission and /map stop (after a grace for messages already on the way)
  // while /scan goes on; new subscriptions resume /tf and /map, the map at once.
  const stopped = ["/tf", "/mission", "/map"];
  // Messages of the dropped subscriptions, counted from 0.5 s after the unsubscribe (those
  // already on the way may still come before).
  const goneIds = new Map();
  const late = new Map();
  let graceOver = false;
  client.off("message", onMessage);
  client.on("message", (event) => {
    const topic = goneIds.get(event.subscriptionId);
    if (topic === undefined) onMessage(event);
    else if (graceOver) late.set(topic, (late.get(topic) ?? 0) + 1);
  });
  for (const [id, c] of [...subscriptions]) {
    if (stopped.includes(c.topic)) {
      client.unsubscribe(id);
      subscriptions.delete(id);
      goneIds.set(id, c.topic);
    }
  }
  await sleep(500);
  graceOver = true;
  const scanBefore = statsOf("/scan").count;
  await sleep(2500);
  for (const topic of stopped) {
    if (late.get(topic)) fail(`${topic}: ${late.get(topic)} messages in the 2.5 s from 0.5 s after its unsubscribe`);
  }
  for (const topic of ["/safe_path"]) {
    if (byTopic.has(topic)) for (const id of ["safe_curve", "waypoints"]) if (!sceneSeen.has(id)) fail(`${topic}: entity ${id} never drawn (no message with a line of two points or more)`);
  }
  if (statsOf("/scan").count - scanBefore < 5) fail(`/scan: ${statsOf("/scan").count - scanBefore} messages in 2.5 s while /tf was unsubscribed`);
  const resumed = ["/tf", "/map"];
  for (const topic of resumed) {
    const s = statsOf(topic);
    s.resubscribedAt = Date.now();
    s.firstAfterResubscribe = null;
    s.sinceResubscribe = 0;
    const c = byTopic.get(topic);
    if (c) subscriptions.set(client.subscribe(c.id), c);
  }
  await sleep(2000);
  if (statsOf("/tf").sinceResubscribe < 10) fail(`/tf: ${statsOf("/tf").sinceResubscribe} messages in 2 s after subscribing again`);
  const mapDelay = statsOf("/map").firstAfterResubscribe;
  if (mapDelay === null || mapDelay > 1500) fail(`/map: ${mapDelay === null ? "nothing" : `the first message ${mapDelay} ms`} after a new subscription (documented: at each subscribe)`);
  else log(`/map came ${mapDelay} ms after a new subscription`);

  for (const [topic, s] of stats) {
    if (s.repeatedStamps) note(`${topic}: ${s.repeatedStamps} messages with the timestamp of the one before (a state sent again)`);
    if (s.stampDiffers) note(`${topic}: ${s.stampDiffers} messages whose header timestamp is not their payload's timestamp`);
  }
  table(Date.now() - subscribedAt);
  client.close();
  await sleep(200);
}

try {
  await main();
} catch (error) {
  failures.push(error.message);
  console.error(`FAIL ${error.message}`);
}
for (const [key, n] of failureCounts) if (n > 3) console.error(`(${n - 3} more like: ${key})`);
if (failures.length) {
  const repeated = [...failureCounts.values()].reduce((a, b) => a + Math.max(0, b - 3), 0);
  console.log(`conformance: FAILED, ${failures.length + repeated} failure(s)`);
  process.exit(1);
}
console.log(`conformance: every check passed${notes.length ? ` (${notes.length} notes)` : ""}`);
process.exit(0);
