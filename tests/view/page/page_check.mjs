// The robot's built-in live view page (view/page/index.html) in headless Chromium, driven by
// playwright-core, against a running view server whose last state the report describes.
//
// usage: node page_check.mjs --url http://127.0.0.1:PORT/ --report DIR/report.json
//                            --screenshot FILE.png [--modules DIR] [--chromium PATH]
//                            [--timeout S] [--tolerance M]
//   --modules: the folder whose node_modules holds playwright-core (default: beside this file).
//   --screenshot: the desktop screenshot; the phone's goes beside it as FILE-phone.png.
//
// The page is opened twice, in a desktop window (1280 x 800) and in a phone held upright
// (390 x 844, touch, 3 device pixels per CSS pixel). Each time it must, within the time limit,
// be connected with the map, a pose and a /mission message decoded, and then:
//   - it asked nothing of any other origin (no fonts, scripts or images from the internet) and
//     logged no console error, threw nothing and noted no decode error in sen3botView.errors;
//   - its pose (base_link in map, from /tf) is within the tolerance of the report's last
//     case's final_pose;
//   - its map geometry equals that of /map as decoded here, on a WebSocket of this check's own;
//   - the canvas, read back pixel by pixel through the page's own world-to-screen transform
//     (sen3botView.toScreen), has the robot's colour inside the footprint at the final pose,
//     dark pixels on walls (cells deep inside occupied areas of /map) and light ones on free
//     floor;
//   - on the phone, the side panel sits below the canvas and the canvas spans the width.
// Exit 0 when both pass, 1 on a failure (every failed check is printed), 2 on bad arguments,
// 77 when the browser is not installed.
import { createRequire } from "node:module";
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";

const SKIP = 77;
// The page draws the robot's footprint (0.455 m x 0.381 m about the axle) filled in this colour.
const ROBOT_RGB = [255, 140, 0];
const FOOTPRINT = { length: 0.455, width: 0.381 };
const REQUIRED_TOPICS = ["/map", "/costmap/global", "/costmap/local", "/scan", "/tf", "/plan", "/safe_path",
                         "/path/driven", "/dwa", "/people", "/stats", "/mission"];

function usage(message) {
  process.stderr.write(`page_check.mjs: ${message}\n`);
  process.exit(2);
}

function parseArguments(argv) {
  const options = {
    url: "", report: "", screenshot: "", modules: path.dirname(fileURLToPath(import.meta.url)),
    chromium: "/usr/bin/chromium", timeout: 60, tolerance: 0.05,
  };
  const keys = ["--url", "--report", "--screenshot", "--modules", "--chromium", "--timeout", "--tolerance"];
  for (let i = 0; i < argv.length; i += 2) {
    const key = argv[i], value = argv[i + 1];
    if (!keys.includes(key)) usage(`unknown argument '${key}'`);
    if (value === undefined) usage(`${key} needs a value`);
    options[key.slice(2)] = ["--timeout", "--tolerance"].includes(key) ? Number(value) : value;
  }
  if (!options.url) usage("--url is required");
  if (!options.report) usage("--report is required");
  if (!options.screenshot) usage("--screenshot is required");
  if (!(options.timeout > 0) || !(options.tolerance > 0)) usage("--timeout and --tolerance must be positive");
  return options;
}

const options = parseArguments(process.argv.slice(2));
const log = (message) => process.stderr.write(`page_check: ${message}\n`);

if (!fs.existsSync(options.chromium)) {
  log(`skipped: no Chromium at ${options.chromium}`);
  process.exit(SKIP);
}
const require = createRequire(path.join(path.resolve(options.modules), "package.json"));
const { chromium } = require("playwright-core");

function finalPose(reportPath) {
  const report = JSON.parse(fs.readFileSync(reportPath, "utf8"));
  const cases = Array.isArray(report.cases) ? report.cases : [];
  if (!cases.length) throw new Error(`${reportPath}: no cases`);
  const last = cases[cases.length - 1];
  const p = last.final_pose;
  if (!p || typeof p.x !== "number" || typeof p.y !== "number") {
    throw new Error(`${reportPath}: case '${last.name}' has no final_pose {x, y, theta}`);
  }
  return { name: last.name, x: p.x, y: p.y, theta: typeof p.theta === "number" ? p.theta : null };
}

// The origin a request goes to; blob: URLs belong to the origin that made them.
function originOf(url) {
  if (url.startsWith("data:")) return null;
  const inner = url.startsWith("blob:") ? url.slice(5) : url;
  const u = new URL(inner);
  const scheme = { "ws:": "http:", "wss:": "https:" }[u.protocol] || u.protocol;
  return `${scheme}//${u.host}`;
}

// Runs in the page: opens a WebSocket of its own to the server, subscribes to /map alone and
// decodes the first message independently of the page's code. Returns the grid's geometry and
// sample cells: walls (occupied with every cell within 2 occupied) and free floor (free with
// every cell within 3 free), spread over the map.
async function independentMap(wsUrl) {
  const grid = await new Promise((resolve, reject) => {
    const ws = new WebSocket(wsUrl, "foxglove.websocket.v1");
    ws.binaryType = "arraybuffer";
    const timer = setTimeout(() => { ws.close(); reject(new Error("no /map within 20 s on a second connection")); }, 20000);
    const subId = 4242;
    ws.onmessage = (event) => {
      if (typeof event.data === "string") {
        const msg = JSON.parse(event.data);
        if (msg.op !== "advertise") return;
        const ch = msg.channels.find((c) => c.topic === "/map");
        if (ch) ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: subId, channelId: ch.id }] }));
        return;
      }
      const bytes = new Uint8Array(event.data);
      const head = new DataView(event.data);
      if (bytes[0] !== 1 || head.getUint32(1, true) !== subId) return;
      clearTimeout(timer);
      ws.close();
      resolve(JSON.parse(new TextDecoder().decode(bytes.subarray(13))));
    };
    ws.onerror = () => { clearTimeout(timer); reject(new Error(`WebSocket ${wsUrl} failed`)); };
  });
  const raw = Uint8Array.from(atob(grid.data), (ch) => ch.charCodeAt(0));
  const field = grid.fields.find((f) => f.name === "occupancy");
  if (!field) throw new Error("/map has no occupancy field");
  const columns = grid.column_count;
  const rows = raw.length / grid.row_stride;
  const at = (c, r) => raw[r * grid.row_stride + c * grid.cell_stride + field.offset];
  const res = grid.cell_size.x;
  const origin = grid.pose.position;
  const all = (c, r, k, value) => {
    for (let dr = -k; dr <= k; ++dr) for (let dc = -k; dc <= k; ++dc) {
      const cc = c + dc, rr = r + dr;
      if (cc < 0 || rr < 0 || cc >= columns || rr >= rows || at(cc, rr) !== value) return false;
    }
    return true;
  };
  const walls = [], free = [];
  for (let r = 0; r < rows; ++r) for (let c = 0; c < columns; ++c) {
    const centre = { x: origin.x + (c + 0.5) * res, y: origin.y + (r + 0.5) * res };
    if (all(c, r, 2, 100)) walls.push(centre);
    else if (all(c, r, 3, 0)) free.push(centre);
  }
  const spread = (list, n) => (list.length <= n ? list : Array.from({ length: n }, (_, i) => list[Math.floor((i + 0.5) * list.length / n)]));
  return { columns, rows: Math.floor(rows), resolution: res, origin: { x: origin.x, y: origin.y },
           orientation: grid.pose.orientation, walls: spread(walls, 24), free: free.length, freeCells: free };
}

// Runs in the page: the canvas's pixels (RGBA) at world points, through sen3botView.toScreen.
function canvasPixels(points) {
  const canvas = document.querySelector("canvas");
  const ctx = canvas.getContext("2d");
  const sx = canvas.width / canvas.clientWidth, sy = canvas.height / canvas.clientHeight;
  return points.map(({ x, y }) => {
    const s = window.sen3botView.toScreen(x, y);
    const px = Math.floor(s.x * sx), py = Math.floor(s.y * sy);
    if (px < 0 || py < 0 || px >= canvas.width || py >= canvas.height) return { x, y, px, py, rgba: null };
    return { x, y, px, py, rgba: Array.from(ctx.getImageData(px, py, 1, 1).data) };
  });
}

const luminance = (rgba) => 0.299 * rgba[0] + 0.587 * rgba[1] + 0.114 * rgba[2];
const near = (rgba, rgb, tolerance) => rgba && rgb.every((v, i) => Math.abs(rgba[i] - v) <= tolerance);
const fmt = (p) => `(${p.x.toFixed(3)}, ${p.y.toFixed(3)})`;

async function checkOne(browser, setup, expected, failures) {
  const fail = (message) => failures.push(`${setup.name}: ${message}`);
  const context = await browser.newContext(setup.context);
  const page = await context.newPage();
  const pageOrigin = originOf(options.url);
  const foreign = [], consoleErrors = [];
  page.on("request", (request) => {
    const origin = originOf(request.url());
    if (origin && origin !== pageOrigin) foreign.push(request.url());
  });
  page.on("websocket", (ws) => {
    const origin = originOf(ws.url());
    if (origin && origin !== pageOrigin) foreign.push(ws.url());
  });
  page.on("console", (message) => { if (message.type() === "error") consoleErrors.push(message.text()); });
  page.on("pageerror", (error) => consoleErrors.push(`uncaught: ${error.message}`));
  try {
    await page.goto(options.url, { waitUntil: "load", timeout: options.timeout * 1000 });
    try {
      await page.waitForFunction(() => {
        const v = window.sen3botView;
        return v && v.connected && v.map && v.pose && (v.received["/mission"] || 0) > 0;
      }, null, { timeout: options.timeout * 1000, polling: 100 });
    } catch {
      const state = await page.evaluate(() => JSON.stringify(window.sen3botView ?? null)).catch(() => "?");
      fail(`the page did not get the map, a pose and /mission within ${options.timeout} s: ${state.slice(0, 600)}`);
      return;
    }
    // The channels that come periodically, then two frames drawn.
    await page.waitForFunction(() => ["/scan", "/stats"].every((t) => (window.sen3botView.received[t] || 0) > 0),
                               null, { timeout: 10000, polling: 100 }).catch(() => {});
    await page.waitForTimeout(500);
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));

    const view = await page.evaluate(() => JSON.parse(JSON.stringify(window.sen3botView)));
    log(`${setup.name}: received ${JSON.stringify(view.received)}`);
    for (const topic of REQUIRED_TOPICS) {
      if (!view.channels.includes(topic)) fail(`channel ${topic} is not advertised (${view.channels.join(" ")})`);
    }
    for (const topic of ["/map", "/tf", "/mission", "/scan", "/stats"]) {
      if (!(view.received[topic] > 0)) fail(`no ${topic} message decoded`);
    }
    if (view.errors.length) fail(`decode errors: ${view.errors.join(" | ")}`);
    if (typeof view.pose.stamp_ns !== "number" || !(view.pose.stamp_ns > 0)) fail(`pose without stamp_ns: ${JSON.stringify(view.pose)}`);
    if (!view.mission || typeof view.mission.state !== "string") fail(`mission without a state: ${JSON.stringify(view.mission)}`);

    const error = Math.hypot(view.pose.x - expected.x, view.pose.y - expected.y);
    log(`${setup.name}: page pose ${fmt(view.pose)} θ ${view.pose.theta.toFixed(3)}, report's ${expected.name} final_pose ` +
        `${fmt(expected)} θ ${expected.theta?.toFixed(3)}: ${error.toFixed(4)} m apart`);
    if (!(error <= options.tolerance)) {
      fail(`the pose ${fmt(view.pose)} is ${error.toFixed(3)} m from the report's final_pose ${fmt(expected)} ` +
           `(tolerance ${options.tolerance} m)`);
    }

    const wsUrl = options.url.replace(/^http/, "ws");
    const map = await page.evaluate(independentMap, wsUrl);
    const same = (a, b) => Math.abs(a - b) < 1e-6;
    if (view.map.columns !== map.columns || view.map.rows !== map.rows || !same(view.map.resolution, map.resolution) ||
        !same(view.map.origin.x, map.origin.x) || !same(view.map.origin.y, map.origin.y)) {
      fail(`the page's map ${JSON.stringify(view.map)} is not /map's (${map.columns} x ${map.rows}, ` +
           `${map.resolution} m, origin ${fmt(map.origin)})`);
    }
    if (map.walls.length < 4) fail(`/map has only ${map.walls.length} cells deep inside walls`);

    // Robot: the centre and points inside the footprint, clear of the nose mark at the front.
    const th = expected.theta ?? view.pose.theta;
    const inside = [[0, 0], [-0.12, 0], [-0.12, 0.11], [-0.12, -0.11], [0, 0.12], [0, -0.12]]
      .map(([fx, fy]) => ({ x: expected.x + Math.cos(th) * fx - Math.sin(th) * fy,
                            y: expected.y + Math.sin(th) * fx + Math.cos(th) * fy }));
    const robot = await page.evaluate(canvasPixels, inside);
    const robotHits = robot.filter((p) => near(p.rgba, ROBOT_RGB, 40)).length;
    if (!near(robot[0].rgba, ROBOT_RGB, 40) || robotHits < robot.length - 1) {
      fail(`the robot's colour rgb(${ROBOT_RGB}) is not drawn at its final pose ${fmt(expected)}: ` +
           robot.map((p) => `${fmt(p)} -> px ${p.px},${p.py} ${JSON.stringify(p.rgba)}`).join("; "));
    }

    // Walls dark; free floor away from the robot and its paths light.
    const walls = await page.evaluate(canvasPixels, map.walls);
    const dark = walls.filter((p) => p.rgba && luminance(p.rgba) < 90);
    if (dark.length < Math.ceil(0.75 * walls.length)) {
      fail(`only ${dark.length} of ${walls.length} wall cells are drawn dark: ` +
           walls.filter((p) => !dark.includes(p)).slice(0, 6).map((p) => `${fmt(p)} ${JSON.stringify(p.rgba)}`).join("; "));
    }
    const far = map.freeCells.filter((c) => Math.hypot(c.x - expected.x, c.y - expected.y) > 1.0);
    const freeSample = far.length <= 24 ? far : Array.from({ length: 24 }, (_, i) => far[Math.floor((i + 0.5) * far.length / 24)]);
    const floor = await page.evaluate(canvasPixels, freeSample);
    const light = floor.filter((p) => p.rgba && luminance(p.rgba) > 200);
    if (freeSample.length && light.length < Math.ceil(0.6 * freeSample.length)) {
      fail(`only ${light.length} of ${freeSample.length} free cells are drawn light`);
    }
    log(`${setup.name}: robot ${robotHits}/${robot.length} pixels in its colour, walls ${dark.length}/${walls.length} dark, ` +
        `floor ${light.length}/${freeSample.length} light`);

    if (setup.phone) {
      const layout = await page.evaluate(() => {
        const c = document.querySelector("canvas").getBoundingClientRect();
        const a = document.querySelector("aside").getBoundingClientRect();
        return { canvas: { top: c.top, bottom: c.bottom, width: c.width, height: c.height }, aside: { top: a.top }, width: innerWidth };
      });
      if (layout.aside.top < layout.canvas.bottom - 1) fail(`the side panel is not below the canvas: ${JSON.stringify(layout)}`);
      if (layout.canvas.width < 0.9 * layout.width || layout.canvas.height < 250) fail(`the canvas is too small: ${JSON.stringify(layout)}`);
    }

    await page.screenshot({ path: setup.screenshot });
    log(`${setup.name}: screenshot ${setup.screenshot}`);
  } finally {
    if (foreign.length) fail(`requests to other origins: ${[...new Set(foreign)].join(", ")}`);
    if (consoleErrors.length) fail(`console errors: ${consoleErrors.join(" | ")}`);
    await context.close();
  }
}

async function main() {
  let expected;
  try {
    expected = finalPose(options.report);
  } catch (error) {
    log(error.message);
    return 1;
  }
  const screenshot = path.resolve(options.screenshot);
  const phoneShot = screenshot.replace(/(\.png)?$/i, "-phone.png");
  const setups = [
    { name: "desktop", screenshot, context: { viewport: { width: 1280, height: 800 } } },
    { name: "phone", phone: true, screenshot: phoneShot,
      context: { viewport: { width: 390, height: 844 }, deviceScaleFactor: 3, isMobile: true, hasTouch: true } },
  ];
  const browser = await chromium.launch({ executablePath: options.chromium, headless: true, args: ["--no-sandbox"] });
  log(`Chromium ${browser.version()}, page ${options.url}`);
  const failures = [];
  try {
    for (const setup of setups) {
      try {
        await checkOne(browser, setup, expected, failures);
      } catch (error) {
        failures.push(`${setup.name}: ${error.stack || error.message}`);
      }
    }
  } finally {
    await browser.close();
  }
  if (failures.length) {
    for (const f of failures) log(`FAILED ${f}`);
    return 1;
  }
  process.stdout.write(`${JSON.stringify({ ok: true, final_pose: expected, screenshots: setups.map((s) => s.screenshot) })}\n`);
  return 0;
}

process.exit(await main());
