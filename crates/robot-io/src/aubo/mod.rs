//! AUBO arms (ARCS controllers): the JSON-RPC client ([`AuboClient`]), the fault-tolerant
//! runner that drives a program move by move ([`run_program`]), and the two controllers behind
//! `maobi robot send --controller aubo` (the [`Controller`](crate::Controller) seam):
//! [`AuboRpc`] (the runner, over JSON-RPC) and [`AuboScript`] (the program as one Lua script on
//! the script port, followed over JSON-RPC).
//!
//! The client speaks one of three [`Transport`](crate::wire::Transport)s: the official SDK's
//! framed protocol on port 30004 (the default: named params, string ids, version query and login
//! first), maobi's earlier line-delimited form (positional params), or JSON-RPC over HTTP on port
//! 9012. The wire formats themselves are in [`crate::wire`] (which knows nothing of this module).

mod client;
mod rpc;
mod run;
mod script;

pub(crate) use client::io_at;
pub use client::{
    AuboClient, JOINT_POSE_TOLERANCE_M, JOINT_POSE_TOLERANCE_RAD, Link, MAX_ID_MISMATCHES, MAX_ROBOT_NAME_LEN,
    METHOD_NOT_FOUND, PATH_APPEND_WAYPOINTS, QUEUE_FULL, check_robot_name, send_script,
};
pub use rpc::{AuboRpc, Motion};
pub use script::{AuboScript, SCRIPT_START_WAIT};

/// Whether path buffers are timed on maobi's nominal AUBO-i5 parameters (`nominal`), and whether
/// joints computed on nominal parameters are accepted (`accept`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct NominalKinematicsPolicy {
    pub(crate) nominal: bool,
    pub(crate) accept: bool,
}
pub use run::{
    CONTROLLER_FK_TOLERANCE_M, CONTROLLER_FK_TOLERANCE_RAD, PATH_VALID_WAIT, REF_TEMPERATURE_C, RunOptions, RunReport,
    run_program,
};
