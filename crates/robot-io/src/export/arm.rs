//! `arm.json`: an arm's kinematic parameters as its controller reported them, the input a
//! path-buffer export computes its joint waypoints with.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::RobotError;
use crate::kinematics::DhParams;

/// What `arm.json` holds: the parameters `RobotConfig.getKinematicsParam(true)` answered (the
/// controller's calibrated values: nominal plus its compensation), and where they came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmKinematics {
    /// The robot's name on the controller.
    pub robot: String,
    /// Where the parameters were read (the controller's address and transport).
    pub source: String,
    /// Whether they are the controller's real (calibrated) parameters; `false` would be the
    /// nominal ones, which [`ArmKinematics::load`] refuses.
    pub real: bool,
    /// The modified-DH parameters.
    pub kinematics: DhParams,
}

impl ArmKinematics {
    /// Reads and validates `arm.json`.
    ///
    /// # Errors
    /// [`RobotError::Read`] / [`RobotError::Json`] when the file cannot be read or is not
    /// this JSON (serde names the field, line and column); [`RobotError::Config`] when a
    /// parameter is not finite or out of range (naming the array and the joint), or when the
    /// parameters are not the controller's real ones (`real: false`).
    pub fn load(path: &Path) -> Result<Self, RobotError> {
        let text = std::fs::read_to_string(path).map_err(|source| RobotError::Read { path: path.into(), source })?;
        let arm: ArmKinematics =
            serde_json::from_str(&text).map_err(|source| RobotError::Json { path: path.into(), source })?;
        arm.validate(path)?;
        Ok(arm)
    }

    /// Checks the parameters (as [`ArmKinematics::load`] does); `path` names the file in errors.
    ///
    /// # Errors
    /// As [`ArmKinematics::load`].
    pub fn validate(&self, path: &Path) -> Result<(), RobotError> {
        let config = |message: String| RobotError::Config { file: PathBuf::from(path), message };
        self.kinematics.validate().map_err(|why| config(format!("kinematics: {why}")))?;
        if !self.real {
            return Err(config(
                "`real` is false: these are not the controller's calibrated parameters (getKinematicsParam(true))"
                    .into(),
            ));
        }
        Ok(())
    }
}
