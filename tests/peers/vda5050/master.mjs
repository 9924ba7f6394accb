// A VDA 5050 2.0.0 master control built on an independent implementation, vda-5050-lib
// (Siemens, MIT), run against the simulated robot over a real MQTT broker.
//
// It waits for the robot to be ONLINE and to report itself localized, assigns a three-node order
// on the lab map, waits for the library to report it processed with both later nodes
// traversed, then initiates a stateRequest and a factsheetRequest and waits for both to be
// FINISHED. On success it prints one JSON line on stdout and exits 0; on a timeout, a rejected
// order or action, or any message of the robot's that fails the library's own 2.0 schema
// validation, it prints the reason on stderr and exits 1 (2: bad arguments).
//
// usage: node master.mjs --broker mqtt://127.0.0.1:PORT --serial r1 [--modules DIR]
//                        [--timeout S] [--map lab]
//   --modules: the folder whose node_modules holds vda-5050-lib (default: beside this file).
//   The environment's VDA5050_BROKER_URL and VDA5050_SERIAL stand in for --broker, --serial.

import { createRequire } from "node:module";
import path from "node:path";
import { fileURLToPath } from "node:url";

const kManufacturer = "Sen3Bot";

function usage(message) {
  process.stderr.write(`master.mjs: ${message}\n`);
  process.exit(2);
}

function parseArguments(argv) {
  const options = {
    broker: process.env.VDA5050_BROKER_URL ?? "",
    serial: process.env.VDA5050_SERIAL ?? "",
    modules: path.dirname(fileURLToPath(import.meta.url)),
    timeout: 180,
    map: "lab",
  };
  for (let i = 0; i < argv.length; ++i) {
    const key = argv[i];
    const value = argv[i + 1];
    if (!["--broker", "--serial", "--modules", "--timeout", "--map"].includes(key)) usage(`unknown argument '${key}'`);
    if (value === undefined) usage(`${key} needs a value`);
    ++i;
    if (key === "--timeout") {
      options.timeout = Number(value);
      if (!(options.timeout > 0)) usage("--timeout needs a positive number of seconds");
    } else {
      options[key.slice(2)] = value;
    }
  }
  if (!options.broker) usage("--broker (or VDA5050_BROKER_URL) is required");
  if (!options.serial) usage("--serial (or VDA5050_SERIAL) is required");
  return options;
}

const options = parseArguments(process.argv.slice(2));
const require = createRequire(path.join(path.resolve(options.modules), "package.json"));
const { MasterController, Topic, createUuid } = require("vda-5050-lib");
const libraryVersion = require("vda-5050-lib/package.json").version;

// Everything the library refused or reported wrong about the robot's messages.
const validationErrors = [];
const agvId = { manufacturer: kManufacturer, serialNumber: options.serial };
const inboundTopics = new Set([Topic.Connection, Topic.State, Topic.Visualization, Topic.Factsheet]);

// The library validates each inbound message with validateTopicObject before any handler sees
// it; on a failure it drops the message and says so on console.error (and in its `debug` log).
// Both are watched: the first names the schema location, the second catches what fails before
// validation (JSON that does not parse).
class CheckingMasterController extends MasterController {
  validateTopicObject(topic, object, vdaVersion) {
    try {
      super.validateTopicObject(topic, object, vdaVersion);
    } catch (error) {
      if (inboundTopics.has(topic)) {
        validationErrors.push({ topic, error: error.message, headerId: object?.headerId ?? null });
        failNow(`the robot's ${topic} message (headerId ${object?.headerId}) fails the library's ` +
                `VDA 5050 ${vdaVersion} validation: ${error.message}\n${JSON.stringify(object)}`);
      }
      throw error;
    }
  }
}

const consoleError = console.error.bind(console);
console.error = (...parts) => {
  consoleError(...parts);
  const text = parts.map(String).join(" ");
  if (text.startsWith("Drop inbound message")) {
    if (!validationErrors.some(e => text.includes(e.error))) validationErrors.push({ topic: null, error: text });
    failNow(`the library dropped a message of the robot's: ${parts.slice(1).join(" ")}`);
  }
};

const started = Date.now();
const round = value => Number(value.toFixed(3));
const elapsed = () => (Date.now() - started) / 1000;
let master;
let finished = false;
let rejectRun;
const failed = new Promise((_, reject) => { rejectRun = reject; });
failed.catch(() => {});

function failNow(message) {
  rejectRun(new Error(message));
}

async function finish(code, line) {
  if (finished) return;
  finished = true;
  if (line) process.stdout.write(`${line}\n`);
  try {
    await Promise.race([master?.stop(), new Promise(resolve => setTimeout(resolve, 2000))]);
  } catch {
    // stopping is best effort; the result is already decided
  }
  process.exit(code);
}

// Resolves with what `start` passes to its resolve callback, rejects after `seconds` naming
// `what`, or as soon as anything fails the run.
function step(what, seconds, start) {
  let timer;
  const timeout = new Promise((_, reject) => {
    timer = setTimeout(() => reject(new Error(`timed out after ${seconds} s waiting for ${what}`)), seconds * 1000);
  });
  const work = new Promise((resolve, reject) => start(resolve, reject));
  return Promise.race([work, timeout, failed]).finally(() => clearTimeout(timer));
}

async function main() {
  const deadline = started + options.timeout * 1000;
  const remaining = () => Math.max(1, (deadline - Date.now()) / 1000);
  master = new CheckingMasterController(
    {
      interfaceName: "uagv",
      vdaVersion: "2.0.0",
      transport: { brokerUrl: options.broker, heartbeat: 15, reconnectPeriod: 1000, connectTimeout: 10000 },
    },
    { targetAgvs: agvId });

  await step(`the broker at ${options.broker}`, remaining(), (resolve, reject) => master.start().then(resolve, reject));

  let lastState;
  let states = 0;
  let factsheets = 0;
  let visualizations = 0;
  const stateListeners = new Set();
  await master.subscribe(Topic.State, agvId, state => {
    lastState = state;
    ++states;
    for (const listener of stateListeners) listener(state);
  });
  await master.subscribe(Topic.Factsheet, agvId, () => { ++factsheets; });
  await master.subscribe(Topic.Visualization, agvId, () => { ++visualizations; });

  // 1. The robot online (its retained connection message) and its first state.
  await step(`${kManufacturer}/${options.serial} to be ONLINE`, remaining(), resolve => {
    master.trackAgvs((id, connectionState) => {
      if (id.manufacturer === agvId.manufacturer && id.serialNumber === agvId.serialNumber &&
          connectionState === "ONLINE") resolve();
    });
  });
  // The robot accepts an order only from where it is (its first node within reach), so the
  // master waits until the robot says it knows where it is.
  const localized = state => state?.agvPosition?.positionInitialized === true &&
    (state.agvPosition.localizationScore === undefined || state.agvPosition.localizationScore > 0);
  await step("a state with the robot localized", remaining(), resolve => {
    if (localized(lastState)) return resolve();
    const listener = state => {
      if (!localized(state)) return;
      stateListeners.delete(listener);
      resolve();
    };
    stateListeners.add(listener);
  });
  const onlineAt = elapsed();

  // 2. An order through three nodes of the lab map, all released, no actions.
  const positions = [["n0", 2.5, 2.0], ["n1", 2.85, 3.5], ["n2", 2.9, 4.25]];
  const nodes = positions.map(([nodeId, x, y], i) => ({
    nodeId,
    sequenceId: 2 * i,
    released: true,
    nodePosition: { x, y, mapId: options.map },
    actions: [],
  }));
  const edges = nodes.slice(1).map((node, i) => ({
    edgeId: `e${i}`,
    sequenceId: 2 * i + 1,
    released: true,
    startNodeId: nodes[i].nodeId,
    endNodeId: node.nodeId,
    actions: [],
  }));
  const order = { orderId: createUuid(), orderUpdateId: 0, nodes, edges };
  const traversed = [];
  const orderStart = Date.now();
  const processed = await step(`order ${order.orderId} to be processed`, remaining(), (resolve, reject) => {
    master.assignOrder(agvId, order, {
      onOrderProcessed: (withError, byCancelation, active, context) => {
        if (withError) {
          reject(new Error(`the robot rejected the order: ${JSON.stringify(withError)}`));
        } else if (byCancelation) {
          reject(new Error("the order was processed by cancelation"));
        } else {
          resolve({ active, state: context.state });
        }
      },
      onNodeTraversed: node => { traversed.push({ nodeId: node.nodeId, atS: (Date.now() - orderStart) / 1000 }); },
    }).then(published => {
      if (published === undefined) reject(new Error("the library discarded the order as a duplicate"));
    }, reject);
  });
  const orderTimeS = (Date.now() - orderStart) / 1000;
  const traversedIds = traversed.map(t => t.nodeId);
  for (const nodeId of ["n1", "n2"]) {
    if (!traversedIds.includes(nodeId)) {
      throw new Error(`the order was processed but node ${nodeId} was never reported traversed ` +
                      `(traversed: ${JSON.stringify(traversedIds)}; last state ${JSON.stringify(processed.state)})`);
    }
  }

  // 3. stateRequest and factsheetRequest, both to FINISHED.
  const factsheetsBefore = factsheets;
  const actions = ["stateRequest", "factsheetRequest"].map(actionType => ({
    actionId: createUuid(),
    actionType,
    blockingType: "NONE",
  }));
  const actionResults = {};
  const instantStart = Date.now();
  await step("stateRequest and factsheetRequest to be FINISHED", remaining(), (resolve, reject) => {
    master.initiateInstantActions(agvId, { instantActions: actions }, {
      onActionStateChanged: (actionState, withError, action) => {
        if (actionState.actionStatus === "FAILED") {
          reject(new Error(`instant action ${action.actionType} FAILED: ${JSON.stringify(withError ?? actionState)}`));
          return;
        }
        if (actionState.actionStatus === "FINISHED" && actionResults[action.actionType] === undefined) {
          actionResults[action.actionType] = (Date.now() - instantStart) / 1000;
          if (actions.every(a => actionResults[a.actionType] !== undefined)) resolve();
        }
      },
      onActionError: (error, action) => {
        reject(new Error(`instant action ${action.actionType} rejected: ${JSON.stringify(error)}`));
      },
    }).catch(reject);
  });
  // The factsheet the request asked for: it must arrive (and pass validation) too.
  await step("the requested factsheet", Math.min(10, remaining()), resolve => {
    const poll = () => (factsheets > factsheetsBefore ? resolve() : setTimeout(poll, 50));
    poll();
  });

  if (validationErrors.length > 0) throw new Error(`validation errors: ${JSON.stringify(validationErrors)}`);
  // Where the robot said it was when the library called the order processed.
  const last = nodes[nodes.length - 1].nodePosition;
  const where = state => {
    const p = state?.agvPosition;
    if (!p) return null;
    return { x: round(p.x), y: round(p.y), driving: state.driving, toLastNodeM: round(Math.hypot(p.x - last.x, p.y - last.y)) };
  };
  const finalPosition = lastState?.agvPosition;
  await finish(0, JSON.stringify({
    result: "ok",
    library: `vda-5050-lib@${libraryVersion}`,
    vdaVersion: "2.0.0",
    agv: agvId,
    onlineAfterS: Number(onlineAt.toFixed(2)),
    orderId: order.orderId,
    orderTimeS: Number(orderTimeS.toFixed(2)),
    orderActiveAfterProcessing: processed.active,
    nodesTraversed: traversed,
    instantActionsFinishedS: Object.fromEntries(Object.entries(actionResults).map(([k, v]) => [k, Number(v.toFixed(2))])),
    atProcessed: where(processed.state),
    finalPosition: finalPosition ? { x: round(finalPosition.x), y: round(finalPosition.y), theta: round(finalPosition.theta), mapId: finalPosition.mapId } : null,
    messages: { states, visualizations, factsheets },
    validationErrors,
  }));
}

main().catch(async error => {
  process.stderr.write(`master.mjs: FAILED after ${elapsed().toFixed(1)} s: ${error.message}\n`);
  if (validationErrors.length > 0) process.stderr.write(`master.mjs: validation errors: ${JSON.stringify(validationErrors)}\n`);
  await finish(1);
});
