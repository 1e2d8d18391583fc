//! How a video's samples encode brightness (issue 14 §4): bit depth, range, the
//! YUV matrix and the transfer function, as the stream declares them.
//!
//! Phones store 8-bit limited range (Y from 16 to 235), full range (0–255, "JPEG"
//! style, `yuvj420p` or `color_range = pc`), or 10-bit (`yuv420p10le`), for HDR
//! with a BT.2020 matrix and the HLG or PQ transfer function. The decoder converts
//! every one of them to 8-bit full-range BGR with the declared matrix and range
//! ([`VideoSignal::configure`] sets libswscale up), so that a surface of one
//! brightness gives the same grey level whatever the storage, before any
//! threshold. The transfer function is reported, not undone: the vision stage
//! reads edges and thresholds found from the clip's own rest frames, on the
//! encoded signal, as for SDR's gamma.

use ff::color::{Range, Space, TransferCharacteristic};
use ff::ffi;
use ff::format::Pixel;
use ff::software::scaling;
use ffmpeg_next as ff;
use serde::{Deserialize, Serialize};

/// What a video stream's samples mean, as recorded in the plan and by `info`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct VideoSignal {
    /// The codec's pixel format, e.g. `yuv420p`, `yuvj420p`, `yuv420p10le`.
    pub pixel_format: String,
    /// Bits per luma sample.
    pub bit_depth: u8,
    /// Full range (0 to 2^depth − 1, JPEG style) rather than limited (16–235 at 8 bits).
    pub full_range: bool,
    /// The YUV → RGB matrix used: "BT.601", "BT.709", "BT.2020", with
    /// "(unspecified)" when the stream does not say and BT.601 is assumed.
    pub matrix: String,
    /// The transfer function declared: "BT.709", "HLG (ARIB STD-B67)",
    /// "PQ (SMPTE ST 2084)", … or "unspecified".
    pub transfer: String,
}

impl std::fmt::Display for VideoSignal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}, {}-bit {} range, {} matrix, transfer {}",
            self.pixel_format,
            self.bit_depth,
            if self.full_range { "full" } else { "limited" },
            self.matrix,
            self.transfer
        )
    }
}

impl VideoSignal {
    /// The signal of frames in `format` with the stream's declared `range`,
    /// `space` and `transfer`.
    pub(super) fn new(
        format: Pixel,
        range: Range,
        space: Space,
        transfer: TransferCharacteristic,
    ) -> Self {
        let bit_depth = format
            .descriptor()
            // SAFETY: libavutil's static descriptor of the format.
            .map_or(8, |d| unsafe { (*d.as_ptr()).comp[0].depth as u8 });
        let jpeg_format = matches!(
            format,
            Pixel::YUVJ420P | Pixel::YUVJ422P | Pixel::YUVJ444P | Pixel::YUVJ440P | Pixel::YUVJ411P
        );
        let matrix = match space {
            Space::BT709 => "BT.709",
            Space::BT2020NCL | Space::BT2020CL => "BT.2020",
            Space::SMPTE240M => "SMPTE 240M",
            Space::FCC => "FCC",
            Space::BT470BG | Space::SMPTE170M => "BT.601",
            _ => "BT.601 (unspecified)",
        };
        let transfer = match transfer {
            TransferCharacteristic::BT709 => "BT.709",
            TransferCharacteristic::SMPTE2084 => "PQ (SMPTE ST 2084)",
            TransferCharacteristic::ARIB_STD_B67 => "HLG (ARIB STD-B67)",
            TransferCharacteristic::SMPTE170M => "BT.601 (SMPTE 170M)",
            TransferCharacteristic::IEC61966_2_1 => "sRGB (IEC 61966-2-1)",
            TransferCharacteristic::BT2020_10 | TransferCharacteristic::BT2020_12 => "BT.2020",
            TransferCharacteristic::Linear => "linear",
            _ => "unspecified",
        };
        Self {
            pixel_format: format!("{format:?}").to_lowercase(),
            bit_depth,
            full_range: jpeg_format || range == Range::JPEG,
            matrix: matrix.into(),
            transfer: transfer.into(),
        }
    }

    /// libswscale's name of the matrix.
    fn sws_matrix(&self) -> i32 {
        match self.matrix.as_str() {
            "BT.709" => ffi::SWS_CS_ITU709,
            "BT.2020" => ffi::SWS_CS_BT2020,
            "SMPTE 240M" => ffi::SWS_CS_SMPTE240M,
            "FCC" => ffi::SWS_CS_FCC,
            _ => ffi::SWS_CS_DEFAULT,
        }
    }

    /// Set a YUV → RGB conversion up for this signal: its matrix and range in, full
    /// range out. Without it libswscale takes every stream but `yuvj*` for limited
    /// range BT.601.
    pub(super) fn configure(&self, context: &mut scaling::Context) -> Result<(), String> {
        // SAFETY: the context is a live SwsContext; the coefficient table is
        // libswscale's static one.
        let ret = unsafe {
            let table = ffi::sws_getCoefficients(self.sws_matrix());
            ffi::sws_setColorspaceDetails(
                context.as_mut_ptr(),
                table,
                i32::from(self.full_range),
                table,
                1,
                0,
                1 << 16,
                1 << 16,
            )
        };
        if ret < 0 {
            Err(format!(
                "libswscale cannot convert {} from {} range with the {} matrix",
                self.pixel_format,
                if self.full_range { "full" } else { "limited" },
                self.matrix
            ))
        } else {
            Ok(())
        }
    }
}
