//! torchvision DenseNet weights.
