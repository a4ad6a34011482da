//! robot-io's tests, one test binary (a `tests/*.rs` file each would link its own), one module
//! per area: programs and their safety check, exports (and real Lua / G-code parsers), ink,
//! the AUBO wire format against the official SDK's captured frames, the runner under faults,
//! the simulator server and its transports, timing and the path buffer.

mod blends;
mod common;
mod exports;
mod external_parsers;
mod framing;
mod ink;
mod path_buffer;
mod robot;
mod runner_faults;
mod safety;
mod script_port;
mod sim_server;
mod timing;
mod transports;
mod ur_hostile;
mod urscript_signatures;
mod wire_golden;
