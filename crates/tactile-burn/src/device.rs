//! The one place that maps a `--device ndarray|flex` choice to a burn device.

use std::fmt;
use std::str::FromStr;

use burn::tensor::Device;

/// The CPU devices burn offers that tactile-rs runs every model on.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum DeviceKind {
    /// burn's NdArray backend: the device the design names (deprecated upstream).
    Ndarray,
    /// burn's Flex backend: its maintained, faster successor; the default for training.
    Flex,
}

impl DeviceKind {
    /// Every supported device, in report order.
    pub const ALL: [DeviceKind; 2] = [DeviceKind::Ndarray, DeviceKind::Flex];

    /// The burn device (without autodiff).
    pub fn device(self) -> Device {
        match self {
            // NdArray is deprecated in burn 0.22 but is the device the design names;
            // this is the one place the deprecation is allowed.
            #[allow(deprecated)]
            DeviceKind::Ndarray => Device::ndarray(),
            DeviceKind::Flex => Device::flex(),
        }
    }

    /// Lower-case name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            DeviceKind::Ndarray => "ndarray",
            DeviceKind::Flex => "flex",
        }
    }
}

impl fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DeviceKind {
    type Err = crate::Error;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "ndarray" => Ok(DeviceKind::Ndarray),
            "flex" => Ok(DeviceKind::Flex),
            other => Err(crate::Error::Config(format!(
                "unknown device '{other}': expected 'ndarray' or 'flex'"
            ))),
        }
    }
}
