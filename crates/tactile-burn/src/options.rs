//! The options layer ([`tactile_options`], burn-free, re-exported here)
//! and the schedule flags every trainer shares ([`schedule_args!`](crate::schedule_args)).

pub use tactile_options::*;

/// A front end's schedule flags for one model (`--max-epochs`,
/// `--patience`, `--batch-size`, `--lr`, `--lr-decay`, `--seed`,
/// `--device`, `--resume`), their defaults from that model's training
/// config: `schedule_args!(Name, Config::new().schedule)` defines `Name`
/// with `schedule(default_lr)` and the public fields `device` and `resume`.
#[macro_export]
macro_rules! schedule_args {
    ($name:ident, $default:expr) => {
        /// The schedule flags, the device and resuming, with this model's defaults.
        #[derive(clap::Args, serde::Serialize, serde::Deserialize, Debug, Clone)]
        pub struct $name {
            /// Upper bound on epochs.
            #[arg(long, default_value_t = $default.max_epochs)]
            pub max_epochs: usize,
            /// Epochs without a better validation loss before stopping.
            #[arg(long, default_value_t = $default.patience)]
            pub patience: usize,
            /// Items per optimiser step.
            #[arg(long, default_value_t = $default.batch_size)]
            pub batch_size: usize,
            /// Learning rate of the first epoch [default: the model's; for the
            /// CAE, Adadelta 1.0 or Adam 0.003].
            #[arg(long)]
            pub lr: Option<f64>,
            /// Learning-rate factor per epoch.
            #[arg(long, default_value_t = $default.lr_decay)]
            pub lr_decay: f64,
            /// Seeds the weights, every shuffle and every split.
            #[arg(long, default_value_t = $default.seed)]
            pub seed: u64,
            /// Training device.
            #[arg(long, value_enum, default_value_t = $crate::DeviceKind::Flex)]
            pub device: $crate::DeviceKind,
            /// Continue from the checkpoint in the output folder.
            #[arg(long)]
            pub resume: bool,
        }

        impl $name {
            /// The schedule, `default_lr` when no `--lr` was given.
            pub fn schedule(&self, default_lr: f64) -> $crate::train::Schedule {
                $crate::train::Schedule::new(
                    self.batch_size,
                    self.max_epochs,
                    self.patience,
                    self.lr.unwrap_or(default_lr),
                )
                .with_lr_decay(self.lr_decay)
                .with_seed(self.seed)
            }
        }
    };
}
