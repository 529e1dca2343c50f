//! Loading the authors' released Keras encoder (`authors-encoder.safetensors`:
//! `convK.weight_hwio` kernels `[3, 3, in, out]` and `convK.bias`) into our
//! [`CaeEncoder`](crate::model::CaeEncoder).

use std::path::Path;

use burn::module::Param;
use burn::nn::conv::Conv2d;
use burn::tensor::{Device, Tensor, TensorData};
use safetensors::SafeTensors;
use tactile_core::Error;

use crate::Result;

use crate::model::{Cae, CaeConfig};

use tactile_burn::module_io::safetensors_f32 as tensor_f32;

fn load_conv(
    conv: &mut Conv2d,
    st: &SafeTensors,
    path: &Path,
    k: usize,
    device: &Device,
) -> Result<()> {
    let (shape, hwio) = tensor_f32(st, path, &format!("conv{k}.weight_hwio"))?;
    let [o, i, kh, kw] = conv.weight.val().dims();
    if shape != [kh, kw, i, o] {
        return Err(crate::Error::Core(Error::shape(
            format!("{}: conv{k}.weight_hwio", path.display()),
            format!("{:?}", [kh, kw, i, o]),
            format!("{shape:?}"),
        )));
    }
    // HWIO -> OIHW. Keras and burn both compute cross-correlation: no flip.
    let mut oihw = vec![0f32; hwio.len()];
    for h in 0..kh {
        for w in 0..kw {
            for ci in 0..i {
                for co in 0..o {
                    oihw[((co * i + ci) * kh + h) * kw + w] =
                        hwio[((h * kw + w) * i + ci) * o + co];
                }
            }
        }
    }
    let (bshape, bias) = tensor_f32(st, path, &format!("conv{k}.bias"))?;
    if bshape != [o] {
        return Err(Error::shape(
            format!("{}: conv{k}.bias", path.display()),
            format!("[{o}]"),
            format!("{bshape:?}"),
        )
        .into());
    }
    conv.weight = Param::from_tensor(Tensor::from_data(
        TensorData::new(oihw, [o, i, kh, kw]),
        device,
    ));
    conv.bias = Some(Param::from_tensor(Tensor::from_data(
        TensorData::new(bias, [o]),
        device,
    )));
    Ok(())
}

/// Channel widths of a released encoder, read from its kernels.
pub fn authors_widths(path: impl AsRef<Path>) -> Result<[usize; 4]> {
    let path = path.as_ref();
    let bytes = tactile_core::io::read_limited(path, tactile_core::io::MAX_WEIGHTS_BYTES)?;
    let st = SafeTensors::deserialize(&bytes)
        .map_err(|e| Error::model(path, format!("not a safetensors file: {e}")))?;
    let mut w = [0; 4];
    for (k, slot) in w.iter_mut().enumerate() {
        let (shape, _) = tensor_f32(&st, path, &format!("conv{}.weight_hwio", k + 1))?;
        *slot = *shape
            .last()
            .ok_or_else(|| Error::model(path, "empty kernel shape"))?;
    }
    Ok(w)
}

/// Build a [`Cae`] whose encoder holds the authors' released weights (the
/// decoder stays freshly initialised: only the encoder was released).
pub fn load_authors_encoder(path: impl AsRef<Path>, device: &Device) -> Result<Cae> {
    let path = path.as_ref();
    let widths = authors_widths(path)?;
    let bytes = tactile_core::io::read_limited(path, tactile_core::io::MAX_WEIGHTS_BYTES)?;
    let st = SafeTensors::deserialize(&bytes)
        .map_err(|e| Error::model(path, format!("not a safetensors file: {e}")))?;
    let mut cae = CaeConfig::new().with_widths(widths).init(device);
    let enc = &mut cae.encoder;
    load_conv(&mut enc.conv1, &st, path, 1, device)?;
    load_conv(&mut enc.conv2, &st, path, 2, device)?;
    load_conv(&mut enc.conv3, &st, path, 3, device)?;
    load_conv(&mut enc.conv4, &st, path, 4, device)?;
    Ok(cae)
}
