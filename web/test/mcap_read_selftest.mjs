// Self-test of web/test/mcap_read.mjs that needs nothing from the C++ side: builds small MCAP
// files in memory with @mcap/core's McapWriter (profile "ros2", one ros2msg schema
// sensor_msgs/msg/JointState with its dependencies, two cdr channels, messages serialized by
// @foxglove/rosmsg2-serialization's MessageWriter), writes them to a temporary directory and runs
// mcap_read.mjs on them as a child process:
//   - a valid file with uncompressed chunks, and one with zstd chunks when Debian's `zstd` program
//     is on PATH (npm has no small, well-known pure-JS zstd compressor; fzstd only decompresses):
//     exit 0, decoded first/last messages equal to what was written, counts, statistics;
//   - the same file cut in the middle of its last chunk (a writer killed by SIGKILL): exit 1
//     without --allow-truncated, exit 0 with it, reading exactly the messages of the earlier chunks;
//   - files the checker must reject (exit 1): wrong profile, channel without offered_qos_profiles,
//     a message with bytes left over after its CDR payload, a corrupted chunk (chunk CRC), a
//     changed byte outside the chunks (data section CRC);
//   - bad usage and a missing file (exit 2).
// Prints one line per check and closes with 'N passed, N failed'; exit 0 when all passed.
//
//   node web/test/mcap_read_selftest.mjs [--keep]     (--keep: leave the temporary files)
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { McapIndexedReader, McapWriter } from '@mcap/core';
import { parse as parseMsgDefinition } from '@foxglove/rosmsg';
import { MessageWriter } from '@foxglove/rosmsg2-serialization';

const here = path.dirname(fileURLToPath(import.meta.url));
const readerScript = path.join(here, 'mcap_read.mjs');
const keep = process.argv.includes('--keep');
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'mcap_read_selftest-'));

// sensor_msgs/msg/JointState as rosbag2 stores it in MCAP ("ros2msg"): the top-level definition,
// then each dependency after a line of 80 '=' and a 'MSG: <type>' line.
const SEPARATOR = '='.repeat(80);
const JOINT_STATE_MSG = [
  '# This is a message that holds data to describe the state of a set of torque controlled joints.',
  'std_msgs/Header header',
  '',
  'string[] name',
  'float64[] position',
  'float64[] velocity',
  'float64[] effort',
  '',
  SEPARATOR,
  'MSG: std_msgs/Header',
  '# Standard metadata for higher-level stamped data types.',
  'builtin_interfaces/Time stamp',
  'string frame_id',
  '',
  SEPARATOR,
  'MSG: builtin_interfaces/Time',
  '# This message communicates ROS Time defined here:',
  'int32 sec',
  'uint32 nanosec',
  '',
].join('\n');

// What rosbag2 puts in a channel's offered_qos_profiles: a YAML list of QoS profiles.
const QOS_YAML = [
  '- history: 3', '  depth: 0', '  reliability: 1', '  durability: 2',
  '  deadline:', '    sec: 9223372036', '    nsec: 854775807',
  '  lifespan:', '    sec: 9223372036', '    nsec: 854775807',
  '  liveliness: 1', '  liveliness_lease_duration:', '    sec: 9223372036', '    nsec: 854775807',
  '  avoid_ros_namespace_conventions: false',
].join('\n');

const TOPICS = ['/joint_states', '/joint_commands'];
const MESSAGE_COUNT = 40; // alternating between the two topics
const T0 = 1_700_000_000_000_000_000n; // ns
const JOINTS = 7;

/** The i-th JointState written (deterministic, with values that are not round numbers). */
function jointState(i) {
  const t = T0 + BigInt(i) * 1_000_000n;
  return {
    header: {
      stamp: { sec: Number(t / 1_000_000_000n), nanosec: Number(t % 1_000_000_000n) },
      frame_id: i % 2 === 0 ? 'base_link' : 'world',
    },
    name: Array.from({ length: JOINTS }, (_, j) => `joint_${j + 1}`),
    position: Array.from({ length: JOINTS }, (_, j) => Math.sin(0.1 * i + j) * 1.5),
    velocity: Array.from({ length: JOINTS }, (_, j) => Math.cos(0.1 * i + j) / 3),
    effort: Array.from({ length: JOINTS }, (_, j) => (i - 20) * 0.25 + j * 1e-3),
  };
}

/** Debian's zstd program as a synchronous compressChunk handler, or undefined if absent. */
function zstdProgram() {
  const probe = spawnSync('zstd', ['--version'], { encoding: 'utf8' });
  if (probe.status !== 0) return undefined;
  return (chunkData) => {
    const run = spawnSync('zstd', ['-q', '-c', '-3'], { input: chunkData, maxBuffer: 1 << 30 });
    if (run.status !== 0) throw new Error(`zstd failed: ${run.stderr}`);
    return { compression: 'zstd', compressedData: new Uint8Array(run.stdout) };
  };
}

/** An in-memory IWritable for McapWriter. */
class MemoryWritable {
  #parts = [];
  #size = 0n;
  async write(buffer) {
    this.#parts.push(buffer.slice()); // the writer reuses its buffer after write() resolves
    this.#size += BigInt(buffer.byteLength);
  }
  position() {
    return this.#size;
  }
  bytes() {
    return Buffer.concat(this.#parts);
  }
}

/** An in-memory IReadable for McapIndexedReader (used here only to locate the last chunk). */
const memoryReadable = (bytes) => ({
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
});

/**
 * Builds an MCAP file. Options break it on purpose for the rejection tests: profile,
 * dropQos (no offered_qos_profiles on channel 1), trailingBytesAt (message index that gets 8
 * extra bytes after its CDR payload).
 */
async function buildMcap({ compressChunk, profile = 'ros2', dropQos = false, trailingBytesAt = -1 } = {}) {
  const writable = new MemoryWritable();
  const writer = new McapWriter({ writable, chunkSize: 2048, compressChunk });
  await writer.start({ profile, library: 'mcap_read_selftest' });
  const schemaId = await writer.registerSchema({
    name: 'sensor_msgs/msg/JointState',
    encoding: 'ros2msg',
    data: new TextEncoder().encode(JOINT_STATE_MSG),
  });
  const channelIds = [];
  for (const [k, topic] of TOPICS.entries()) {
    const metadata = new Map(dropQos && k === 1 ? [] : [['offered_qos_profiles', QOS_YAML]]);
    channelIds.push(await writer.registerChannel({ schemaId, topic, messageEncoding: 'cdr', metadata }));
  }
  const cdr = new MessageWriter(parseMsgDefinition(JOINT_STATE_MSG, { ros2: true }));
  for (let i = 0; i < MESSAGE_COUNT; i++) {
    let data = cdr.writeMessage(jointState(i));
    if (i === trailingBytesAt) data = Buffer.concat([data, Buffer.alloc(8, 0xab)]);
    const time = T0 + BigInt(i) * 1_000_000n;
    await writer.addMessage({
      channelId: channelIds[i % 2],
      sequence: i,
      logTime: time,
      publishTime: time,
      data,
    });
  }
  await writer.end();
  return writable.bytes();
}

/** Runs mcap_read.mjs; returns {status, json (parsed stdout, if any), stderr}. */
function runReader(args) {
  const run = spawnSync(process.execPath, [readerScript, ...args], { encoding: 'utf8', maxBuffer: 1 << 28 });
  let json;
  try {
    json = JSON.parse(run.stdout);
  } catch {
    json = undefined;
  }
  return { status: run.status, json, stderr: run.stderr };
}

let passed = 0;
let failed = 0;
/** One named check: fn throws (assert) on failure. */
function check(name, fn) {
  try {
    fn();
    passed++;
    console.log(`ok   ${name}`);
  } catch (error) {
    failed++;
    console.log(`FAIL ${name}\n     ${String(error.message).split('\n').join('\n     ')}`);
  }
}

/** The JSON form mcap_read.mjs prints for a written message (typed arrays already plain). */
const expectedJson = (i) => JSON.parse(JSON.stringify(jointState(i)));

/** Expected per-channel view of messages [0, n): counts, times, first and last decoded message. */
function expectedChannels(n) {
  return TOPICS.map((topic, k) => {
    const indexes = Array.from({ length: n }, (_, i) => i).filter((i) => i % 2 === k);
    const first = indexes[0];
    const last = indexes[indexes.length - 1];
    return {
      topic,
      count: indexes.length,
      first_log_time_ns: (T0 + BigInt(first) * 1_000_000n).toString(),
      last_log_time_ns: (T0 + BigInt(last) * 1_000_000n).toString(),
      first_message: expectedJson(first),
      last_message: expectedJson(last),
    };
  });
}

function checkChannels(label, json, n) {
  check(`${label}: two channels, cdr, schema sensor_msgs/msg/JointState`, () => {
    assert.equal(json.channels.length, 2);
    for (const c of json.channels) {
      assert.equal(c.encoding, 'cdr');
      assert.equal(c.schema, 'sensor_msgs/msg/JointState');
    }
  });
  const expected = expectedChannels(n);
  for (const [k, e] of expected.entries()) {
    const c = json.channels[k];
    check(`${label}: ${e.topic} count ${e.count}, log times, decoded first/last messages`, () => {
      assert.equal(c.topic, e.topic);
      assert.equal(c.count, e.count);
      assert.equal(c.first_log_time_ns, e.first_log_time_ns);
      assert.equal(c.last_log_time_ns, e.last_log_time_ns);
      assert.deepEqual(c.first_message, e.first_message);
      assert.deepEqual(c.last_message, e.last_message);
    });
  }
}

async function main() {
  const compressors = [['uncompressed', undefined]];
  const zstd = zstdProgram();
  if (zstd) compressors.push(['zstd', zstd]);
  else console.log('note: no `zstd` program on PATH: zstd chunks not tested (apt-get install zstd)');

  for (const [label, compressChunk] of compressors) {
    // --- A valid file: everything must pass and decode to what was written. ---
    const bytes = await buildMcap({ compressChunk });
    const file = path.join(tmp, `valid_${label}.mcap`);
    fs.writeFileSync(file, bytes);
    const outJson = path.join(tmp, `valid_${label}.json`);
    const valid = runReader([file, '--json', outJson]);
    check(`${label}: valid file exits 0 with a JSON report`, () => {
      assert.equal(valid.status, 0, `status ${valid.status}; stderr ${valid.stderr}; problems ${JSON.stringify(valid.json?.problems)}`);
      assert.ok(valid.json, 'stdout is JSON');
      assert.deepEqual(JSON.parse(fs.readFileSync(outJson, 'utf8')), valid.json, '--json file equals stdout');
    });
    if (!valid.json) continue;
    check(`${label}: indexed, profile ros2, library, no problems or decode failures`, () => {
      assert.equal(valid.json.indexed, true);
      assert.equal(valid.json.profile, 'ros2');
      assert.equal(valid.json.library, 'mcap_read_selftest');
      assert.deepEqual(valid.json.problems, []);
      assert.deepEqual(valid.json.decode_failures, []);
      assert.equal(valid.json.decode_failure_count, 0);
    });
    const compressionName = compressChunk ? 'zstd' : '';
    check(`${label}: several chunks, all compressed "${compressionName}", statistics and summary offsets`, () => {
      assert.ok(valid.json.chunk_count >= 3, `chunk_count ${valid.json.chunk_count}`);
      assert.deepEqual(valid.json.chunk_compression, { [compressionName]: valid.json.chunk_count });
      assert.equal(valid.json.statistics.messageCount, String(MESSAGE_COUNT));
      assert.ok(valid.json.summary_offset_groups.includes('CHUNK_INDEX'));
      assert.deepEqual(valid.json.crc, { summary: 'ok', data_section: 'ok', chunks_checked: valid.json.chunk_count, chunks_without_crc: 0 });
    });
    checkChannels(label, valid.json, MESSAGE_COUNT);

    // --- The same file cut in the middle of its last chunk. ---
    const reader = await McapIndexedReader.Initialize({ readable: memoryReadable(bytes) });
    const lastChunk = reader.chunkIndexes[reader.chunkIndexes.length - 1];
    const cut = Number(lastChunk.chunkStartOffset + lastChunk.chunkLength / 2n);
    // Messages of the earlier chunks: log times strictly increase, so those before the last chunk's.
    const kept = Array.from({ length: MESSAGE_COUNT }, (_, i) => T0 + BigInt(i) * 1_000_000n)
      .filter((t) => t < lastChunk.messageStartTime).length;
    const truncated = path.join(tmp, `truncated_${label}.mcap`);
    fs.writeFileSync(truncated, bytes.subarray(0, cut));
    const strict = runReader([truncated]);
    check(`${label}: truncated file (cut at ${cut} of ${bytes.byteLength} bytes) exits 1 without --allow-truncated`, () => {
      assert.equal(strict.status, 1, `status ${strict.status}; stderr ${strict.stderr}`);
      assert.equal(strict.json.indexed, false);
      assert.ok(strict.json.problems.some((p) => p.startsWith('indexed read failed')), JSON.stringify(strict.json.problems));
    });
    const lenient = runReader([truncated, '--allow-truncated']);
    check(`${label}: truncated file exits 0 with --allow-truncated, streamed (indexed false, incomplete)`, () => {
      assert.equal(lenient.status, 0, `status ${lenient.status}; stderr ${lenient.stderr}; problems ${JSON.stringify(lenient.json?.problems)}`);
      assert.equal(lenient.json.indexed, false);
      assert.equal(lenient.json.complete, false);
      assert.ok(lenient.json.unparsed_tail_bytes > 0);
      assert.equal(lenient.json.chunk_count, reader.chunkIndexes.length - 1);
      assert.ok(kept > 0 && kept < MESSAGE_COUNT, `kept ${kept}`);
    });
    if (lenient.json) checkChannels(`${label} truncated (${kept} messages kept)`, lenient.json, kept);
    const lenientComplete = runReader([file, '--allow-truncated']);
    check(`${label}: --allow-truncated on the complete file still reads it indexed`, () => {
      assert.equal(lenientComplete.status, 0);
      assert.equal(lenientComplete.json.indexed, true);
    });

    // --- A corrupted byte inside the first chunk: the chunk CRC must catch it. ---
    const corrupt = Buffer.from(bytes);
    const firstChunk = reader.chunkIndexes[0];
    corrupt[Number(firstChunk.chunkStartOffset + firstChunk.chunkLength) - 40] ^= 0x5a;
    const corruptFile = path.join(tmp, `corrupt_${label}.mcap`);
    fs.writeFileSync(corruptFile, corrupt);
    const corrupted = runReader([corruptFile]);
    check(`${label}: a corrupted chunk exits 1 with a CRC or decompression problem`, () => {
      assert.equal(corrupted.status, 1, `status ${corrupted.status}; stderr ${corrupted.stderr}`);
      assert.ok(corrupted.json.problems.some((p) => /CRC|zstd|decompress|invalid|offset/i.test(p)), JSON.stringify(corrupted.json.problems));
    });
  }

  // --- Files the checker must reject. ---
  // A changed byte outside any chunk (in the Header's library string): only the data section CRC
  // (DataEnd), which McapIndexedReader does not check itself, can see it.
  const tampered = await buildMcap();
  tampered[tampered.indexOf('mcap_read_selftest')] = 'M'.charCodeAt(0);
  const tamperedFile = path.join(tmp, 'tampered_header.mcap');
  fs.writeFileSync(tamperedFile, tampered);
  const tamperedRun = runReader([tamperedFile]);
  check('a changed byte in the Header exits 1 on the data section CRC', () => {
    assert.equal(tamperedRun.status, 1);
    assert.equal(tamperedRun.json.crc.data_section, 'mismatch');
    assert.match(tamperedRun.json.problems.join('\n'), /data_section_crc/);
  });

  const badFile = path.join(tmp, 'bad.mcap');
  fs.writeFileSync(badFile, await buildMcap({ profile: '', dropQos: true, trailingBytesAt: 5 }));
  const bad = runReader([badFile]);
  check('bad file (profile "", no QoS metadata, 8 trailing bytes on message 5) exits 1 with each problem', () => {
    assert.equal(bad.status, 1);
    const problems = bad.json.problems.join('\n');
    assert.match(problems, /profile is "", expected "ros2"/);
    assert.match(problems, /channel 1 \(\/joint_commands\) has no "offered_qos_profiles"/);
    assert.equal(bad.json.decode_failure_count, 1);
    assert.equal(bad.json.decode_failures[0].sequence, 5);
    assert.match(bad.json.decode_failures[0].error, /8 bytes left over/);
  });

  // --- Bad usage and unreadable files: exit 2. ---
  check('no arguments exits 2', () => assert.equal(runReader([]).status, 2));
  check('a missing file exits 2', () => assert.equal(runReader([path.join(tmp, 'missing.mcap')]).status, 2));
  const notMcap = path.join(tmp, 'not_mcap.mcap');
  fs.writeFileSync(notMcap, 'this is not an MCAP file at all, just some text\n');
  check('a file that is not MCAP exits 2, also with --allow-truncated', () => {
    assert.equal(runReader([notMcap]).status, 2);
    assert.equal(runReader([notMcap, '--allow-truncated']).status, 2);
  });

  if (keep) console.log(`files kept in ${tmp}`);
  else fs.rmSync(tmp, { recursive: true, force: true });
  console.log(`${passed} passed, ${failed} failed`);
  process.exit(failed === 0 ? 0 : 1);
}

await main();
