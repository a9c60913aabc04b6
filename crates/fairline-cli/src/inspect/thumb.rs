//! Thumbnails of the report's pictures: a PNG scaled down by averaging
//! whole blocks of pixels.

use std::path::Path;

/// Writes `to`: the PNG `from` scaled down by an integer factor so that it
/// is at most `width` pixels across (each pixel the mean of its block);
/// a picture narrower than `width` is copied as it is.
pub fn write_thumbnail(from: &Path, to: &Path, width: u32) -> anyhow::Result<()> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(from)?));
    let mut reader = decoder.read_info()?;
    let mut buf = vec![0; reader.output_buffer_size().unwrap_or(0)];
    let info = reader.next_frame(&mut buf)?;
    let channels = match info.color_type {
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Indexed => anyhow::bail!("indexed PNG"),
    };
    if info.bit_depth != png::BitDepth::Eight {
        anyhow::bail!("not an 8-bit PNG");
    }
    let (w, h) = (info.width, info.height);
    let factor = w.div_ceil(width.max(1)).max(1);
    let (tw, th) = ((w / factor).max(1), (h / factor).max(1));
    let mut out = vec![0u8; (tw * th * channels) as usize];
    let stride = info.line_size;
    for ty in 0..th {
        for tx in 0..tw {
            for c in 0..channels {
                let mut sum = 0u32;
                for y in ty * factor..(ty + 1) * factor {
                    for x in tx * factor..(tx + 1) * factor {
                        sum += u32::from(buf[(y as usize) * stride + (x * channels + c) as usize]);
                    }
                }
                out[((ty * tw + tx) * channels + c) as usize] = (sum / (factor * factor)) as u8;
            }
        }
    }
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, tw, th);
        enc.set_color(info.color_type);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header()?;
        writer.write_image_data(&out)?;
    }
    std::fs::write(to, bytes)?;
    Ok(())
}
