//! AUBO arms (ARCS controllers): the JSON-RPC client ([`AuboClient`]), the fault-tolerant
//! runner that drives a program move by move ([`run_program`]), and the controller behind
//! `maobi robot send --controller aubo` ([`AuboRpc`]: the runner behind the
//! [`Controller`](crate::Controller) seam).
//!
//! The client speaks one of three [`Transport`](crate::wire::Transport)s: the official SDK's
//! framed protocol on port 30004 (the default: named params, string ids, version query and login
//! first), maobi's earlier line-delimited form (positional params), or JSON-RPC over HTTP on port
//! 9012. The wire formats themselves are in [`crate::wire`] (which knows nothing of this module).

mod client;
mod rpc;
mod run;

pub(crate) use client::io_at;
pub use client::{
    AuboClient, JOINT_POSE_TOLERANCE_M, JOINT_POSE_TOLERANCE_RAD, Link, MAX_ID_MISMATCHES, MAX_ROBOT_NAME_LEN,
    METHOD_NOT_FOUND, PATH_APPEND_WAYPOINTS, QUEUE_FULL, check_robot_name, send_script,
};
pub use rpc::{AuboRpc, Motion};
pub use run::{
    CONTROLLER_FK_TOLERANCE_M, CONTROLLER_FK_TOLERANCE_RAD, PATH_VALID_WAIT, REF_TEMPERATURE_C, RunOptions, RunReport,
    run_program,
};
