/* kingen_wasm.js: the kinematics of a kingen robot in JavaScript, from its C library
 * (kingen_<name>.h and .c, generated and verified by kingen) compiled to WebAssembly
 * (kingen_<name>.wasm, `kingen package ROBOT --host wasm`). No dependencies: a browser's or
 * Node's WebAssembly. Load it as a classic <script> (it defines globalThis.KingenWasm) or with
 * require() (module.exports).
 *
 *   const kin = KingenWasm.create(bytes, {dof: 6, postures: 1});   // or await KingenWasm.instantiate(...)
 *   kin.inverse([0, 0, 800, 5, 0, 0], 0)   // -> {joints: [...], warning: "WARN_GOOD_SOLUTION"}
 *   kin.inverseAll([0, 0, 800, 5, 0, 0])   // -> {joints: [[...] per posture], warnings: [...], status: 0}
 *   kin.forward(joints, 0, seedPose)       // -> {pose: [x, y, z, roll, pitch, yaw], matrix, status, iterations}
 *   kin.machinePose(pose)                  // a machine with task coordinates: -> {pose, matrix, status}, else null
 *   kin.setGeometry(bytes)                 // a calibrated geometry struct's bytes: every later call uses it
 *
 * A pose is an array of 6 numbers and joints of dof numbers: any other length is a RangeError.
 * Where the C function finds no pose (forward's status != 0; machinePose's -1 or
 * WARN_UNREACHABLE 2), pose and matrix are null.
 *
 * Units and frames (kingen's conventions, docs/reference/conventions.md): a pose is the platform
 * (a wrist's: the tool) frame in the base frame as x y z in mm and roll pitch yaw in degrees,
 * R = Rz(yaw) Ry(pitch) Rx(roll). Joints are the library's: mm (prismatic) and radians (revolute),
 * in the robot file's order, as `kingen solve --json` writes them. A posture is 0 .. postures - 1.
 * Warnings are kingen's codes by name: WARN_GOOD_SOLUTION 0, WARN_JOINT_LIMITS_EXCEEDED 1,
 * WARN_UNREACHABLE 2, WARN_SINGULAR_SOLUTION 5.
 *
 * The module (clang --target=wasm32-wasi -mexec-model=reactor, wasi-libc) exports:
 *   memory                        its linear memory
 *   _initialize()                 run once before any call (its constructors)
 *   malloc(size) -> pointer, free(pointer)   the module's own allocator: this glue takes its
 *                                 buffers (and a calibrated geometry's copy) from it
 *   __indirect_function_table     its function table (growable: the batch driver's pointers)
 *   <prefix>_inverse(geometry, pose, joints, warnings) -> int   every posture: joints[i * postures + k]
 *   <prefix>_inverse_posture(geometry, pose, posture, joints) -> int   the posture's warning, -1 out of range
 *   <prefix>_forward(geometry, joints, posture, seed, pose, iterations) -> int   0, -1 bad input, -2 no pose
 *   <prefix>_jacobian(geometry, pose, posture, jacobian) -> int   jacobian[i * 6 + c]
 *   <prefix>_direct_index, _machine_pose, _static_loads   where the robot's header declares them
 *   <prefix>_default_geometry     global: the address of the robot file's geometry struct
 *   <prefix>_build_info           global: the address of "robot, definition sha256, kingen version"
 *   kingen_c_inverse_batch, kingen_c_forward_batch, kingen_c_machine_pose_batch,
 *   kingen_c_timed_batch          kingen's batch driver (what `kingen verify --host wasm` calls)
 * Pointers are byte offsets into memory (i32); poses are 16 doubles, the homogeneous matrix row
 * by row (pose[4 * r + c]); every double is little-endian float64, every int int32.
 * Imports: wasi_snapshot_preview1.clock_time_get (the timed batch's clock) only; this glue
 * supplies it, and a stub answering ENOSYS for any other WASI function a module asks for.
 */
(function (root) {
    "use strict";

    var WARNINGS = {0: "WARN_GOOD_SOLUTION", 1: "WARN_JOINT_LIMITS_EXCEEDED", 2: "WARN_UNREACHABLE",
                    5: "WARN_SINGULAR_SOLUTION"};
    var ENOSYS = 52;
    var DEGREE = Math.PI / 180;

    /* The row-major homogeneous matrix (16 numbers) of a pose [x, y, z, roll, pitch, yaw] (mm, degrees). */
    function poseMatrix(pose) {
        var r = pose[3] * DEGREE, p = pose[4] * DEGREE, y = pose[5] * DEGREE;
        var cr = Math.cos(r), sr = Math.sin(r), cp = Math.cos(p), sp = Math.sin(p), cy = Math.cos(y), sy = Math.sin(y);
        return [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr, pose[0],
                sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr, pose[1],
                -sp, cp * sr, cp * cr, pose[2],
                0, 0, 0, 1];
    }

    /* The pose [x, y, z, roll, pitch, yaw] (mm, degrees; pitch in [-90, 90]) of a row-major matrix. */
    function matrixPose(m) {
        return [m[3], m[7], m[11], Math.atan2(m[9], m[10]) / DEGREE,
                Math.asin(Math.min(1, Math.max(-1, -m[8]))) / DEGREE, Math.atan2(m[4], m[0]) / DEGREE];
    }

    function wasiImports(module, memoryOf) {
        var wasi = {};
        WebAssembly.Module.imports(module).forEach(function (entry) {
            if (entry.module === "wasi_snapshot_preview1" && entry.kind === "function")
                wasi[entry.name] = function () { return ENOSYS; };
        });
        wasi.clock_time_get = function (clock, precision, out) {
            var now = typeof performance !== "undefined" ? performance.now() : Date.now();
            new DataView(memoryOf().buffer).setBigUint64(out, BigInt(Math.round(now * 1e6)), true);
            return 0;
        };
        return {wasi_snapshot_preview1: wasi};
    }

    function Kingen(module, meta) {
        var self = this, instance;
        instance = new WebAssembly.Instance(module, wasiImports(module, function () { return self.exports.memory; }));
        this.exports = instance.exports;
        this.prefix = meta.prefix || Object.keys(this.exports).filter(function (name) {
            return /_inverse_posture$/.test(name);
        })[0].replace(/_inverse_posture$/, "");
        this.dof = meta.dof;
        this.postures = meta.postures;
        if (this.exports._initialize) this.exports._initialize();
        this.geometry = this.exports[this.prefix + "_default_geometry"].value >>> 0;
        /* One block from the module's malloc: pose[16], seed[16], out[16] doubles,
         * joints[dof * postures] doubles, warnings[postures] ints, iterations int. */
        var doubles = 48 + this.dof * this.postures, base = this.allocate(8 * doubles + 4 * this.postures + 4);
        this.at = {pose: base, seed: base + 128, out: base + 256, joints: base + 384,
                   warnings: base + 8 * doubles, iterations: base + 8 * doubles + 4 * this.postures};
    }

    /* The address of size bytes from the module's own malloc (an Error if it has none or it fails). */
    Kingen.prototype.allocate = function (size) {
        if (typeof this.exports.malloc !== "function")
            throw new Error("the module exports no malloc: build it with kingen build --host wasm");
        var address = this.exports.malloc(size) >>> 0;
        if (address === 0 || address + size > this.exports.memory.buffer.byteLength)
            throw new Error("the module's malloc(" + size + ") gave no block of its memory");
        return address;
    };

    /* Every later call takes this geometry: bytes (ArrayBuffer or typed array) of the header's
     * geometry struct, copied into a block of the module's malloc (the previous copy freed). */
    Kingen.prototype.setGeometry = function (bytes) {
        var view = ArrayBuffer.isView(bytes) ? new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength)
                                             : new Uint8Array(bytes);
        var address = this.allocate(view.length);
        new Uint8Array(this.exports.memory.buffer, address, view.length).set(view);
        if (this.copied) this.exports.free(this.copied);
        this.geometry = this.copied = address;
    };

    /* The default geometry struct's first size bytes, copied (to change and pass to setGeometry). */
    Kingen.prototype.defaultGeometry = function (size) {
        var address = this.exports[this.prefix + "_default_geometry"].value >>> 0;
        return new Uint8Array(this.exports.memory.buffer.slice(address, address + size));
    };

    /* values as an array of count numbers; a RangeError naming what for any other length. */
    function numbers(values, count, what) {
        if (!values || values.length !== count)
            throw new RangeError(what + ": give " + count + " numbers, not " + (values ? values.length : values));
        return values;
    }

    /* The result of a C function that wrote the matrix at out, or found none (found false): nulls. */
    Kingen.prototype.answer = function (found, status) {
        var matrix = found ? Array.from(this.doubles(this.at.out, 16)) : null;
        return {pose: matrix && matrixPose(matrix), matrix: matrix, status: status};
    };

    Kingen.prototype.doubles = function (address, count) {
        return new Float64Array(this.exports.memory.buffer, address, count);
    };

    Kingen.prototype.ints = function (address, count) {
        return new Int32Array(this.exports.memory.buffer, address, count);
    };

    Kingen.prototype.posture = function (posture) {
        if (!(posture >= 0 && posture < this.postures && posture === Math.floor(posture)))
            throw new RangeError("posture " + posture + ": the robot's are 0 .. " + (this.postures - 1));
        return posture;
    };

    /* One posture's joints at pose [x y z roll pitch yaw] (mm, degrees): {joints, warning}. */
    Kingen.prototype.inverse = function (pose, posture) {
        this.doubles(this.at.pose, 16).set(poseMatrix(numbers(pose, 6, "pose")));
        var code = this.exports[this.prefix + "_inverse_posture"](this.geometry, this.at.pose, this.posture(posture),
                                                                  this.at.joints);
        return {joints: Array.from(this.doubles(this.at.joints, this.dof)), warning: WARNINGS[code]};
    };

    /* Every posture at pose: {joints: [posture][joint], warnings: [posture], status: 0 or 1 (none reachable)}. */
    Kingen.prototype.inverseAll = function (pose) {
        this.doubles(this.at.pose, 16).set(poseMatrix(numbers(pose, 6, "pose")));
        var status = this.exports[this.prefix + "_inverse"](this.geometry, this.at.pose, this.at.joints,
                                                             this.at.warnings);
        var values = this.doubles(this.at.joints, this.dof * this.postures), joints = [], k, i;
        for (k = 0; k < this.postures; k++) {
            joints.push([]);
            for (i = 0; i < this.dof; i++) joints[k].push(values[i * this.postures + k]);
        }
        return {joints: joints, warnings: Array.from(this.ints(this.at.warnings, this.postures), function (code) {
            return WARNINGS[code];
        }), status: status};
    };

    /* The pose with these joints (the library's units) on posture's branches, nearest seed (a pose,
     * mm and degrees): {pose, matrix (row-major, 16), status (0, -1 bad input, -2 none), iterations};
     * pose and matrix null when status is not 0. */
    Kingen.prototype.forward = function (joints, posture, seed) {
        this.doubles(this.at.joints, this.dof).set(numbers(joints, this.dof, "joints"));
        this.doubles(this.at.seed, 16).set(poseMatrix(numbers(seed, 6, "seed")));
        this.ints(this.at.iterations, 1)[0] = 0;
        var status = this.exports[this.prefix + "_forward"](this.geometry, this.at.joints, this.posture(posture),
                                                            this.at.seed, this.at.out, this.at.iterations);
        var answer = this.answer(status === 0, status);
        answer.iterations = this.ints(this.at.iterations, 1)[0];
        return answer;
    };

    /* A machine with task coordinates (the module exports <prefix>_machine_pose): the machine's whole
     * pose for the task coordinates of pose (mm, degrees), its other coordinates solved from its
     * constraints: {pose, matrix (row-major, 16), status (the C function's: a warning code, or -1 for
     * a pose holding NaN or infinity)}, pose and matrix null for -1 and WARN_UNREACHABLE (2: no pose
     * has these task coordinates); null for a robot without one. */
    Kingen.prototype.machinePose = function (pose) {
        var solve = this.exports[this.prefix + "_machine_pose"];
        if (!solve) return null;
        this.doubles(this.at.pose, 16).set(poseMatrix(numbers(pose, 6, "pose")));
        var status = solve(this.at.pose, this.at.out);
        return this.answer(status !== -1 && status !== 2, status);
    };

    var KingenWasm = {
        WARNINGS: WARNINGS,
        poseMatrix: poseMatrix,
        matrixPose: matrixPose,
        /* Compile and instantiate synchronously (bytes: ArrayBuffer or typed array; meta: {dof, postures}). */
        create: function (bytes, meta) { return new Kingen(new WebAssembly.Module(bytes), meta); },
        /* The same, compiling off the main thread: a Promise of the instance. */
        instantiate: function (bytes, meta) {
            return WebAssembly.compile(bytes).then(function (module) { return new Kingen(module, meta); });
        }
    };
    if (typeof module !== "undefined" && module.exports) module.exports = KingenWasm;
    root.KingenWasm = KingenWasm;
})(typeof globalThis !== "undefined" ? globalThis : this);
