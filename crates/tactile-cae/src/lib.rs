//! Paper A's convolutional autoencoder: the model (Table I), loading the
//! authors' released encoder, training (Adadelta, early stopping,
//! resumable), encoding datasets to feature CSVs, and a shallow classifier
//! head that proves the features.

pub mod artifact;
pub mod authors;
pub mod data;
pub mod encode;
pub mod head;
pub mod model;
pub mod training;

pub use artifact::CaeArtifact;
pub use model::{Cae, CaeConfig, CaeDecoder, CaeEncoder};
