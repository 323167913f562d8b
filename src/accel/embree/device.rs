//! An Embree device (`RTCDevice`): `rtcNewDevice`, an error callback installed with
//! `rtcSetDeviceErrorFunction` that records every error message, and `rtcGetDeviceError`
//! checks that turn Embree's error state into [`AccelError::Embree`].

use super::sys;
use crate::accel::AccelError;
use std::ffi::{c_char, c_void, CStr};
use std::sync::Mutex;

/// Messages the error callback received, oldest first.
type ErrorLog = Mutex<Vec<String>>;

/// An owned Embree device with an error log. Scenes keep their device alive through an `Arc`.
pub struct Device {
    raw: sys::RTCDevice,
    /// Boxed so that its address, handed to Embree as the callback's user pointer, is stable.
    log: Box<ErrorLog>,
}

// SAFETY: Embree's device is internally synchronised: creating scenes and geometries on it,
// and its reference counting, are documented as thread-safe. The only state on our side is the
// error log, behind a Mutex. The handle is only released in `Drop`, which has exclusive access.
unsafe impl Send for Device {}
// SAFETY: as above; `&Device` only allows calls Embree permits concurrently.
unsafe impl Sync for Device {}

/// Called by Embree (from any thread, including its build workers) when an API call fails.
unsafe extern "C" fn record_error(user: *mut c_void, code: sys::RTCError, message: *const c_char) {
    let text = if message.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string that lives for the duration of the call.
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    };
    // SAFETY: `user` is the address of the boxed log of the `Device` that installed this
    // callback; the callback is removed in `Drop` before the box is freed.
    let log = unsafe { &*(user as *const ErrorLog) };
    log.lock().unwrap_or_else(|e| e.into_inner()).push(format!("{} ({text})", error_name(code)));
}

/// Embree's name for an error code (`rtcGetErrorString` exists only in Embree 4).
fn error_name(code: sys::RTCError) -> String {
    match code {
        sys::RTC_ERROR_NONE => "no error".into(),
        sys::RTC_ERROR_UNKNOWN => "unknown error".into(),
        sys::RTC_ERROR_INVALID_ARGUMENT => "invalid argument".into(),
        sys::RTC_ERROR_INVALID_OPERATION => "invalid operation".into(),
        sys::RTC_ERROR_OUT_OF_MEMORY => "out of memory".into(),
        sys::RTC_ERROR_UNSUPPORTED_CPU => "unsupported CPU".into(),
        sys::RTC_ERROR_CANCELLED => "cancelled".into(),
        other => format!("error code {other}"),
    }
}

impl Device {
    /// Creates a device with an Embree configuration string (e.g. `c"threads=4,verbose=0"`).
    pub fn new(config: &CStr) -> Result<Self, AccelError> {
        // SAFETY: `config` is a valid NUL-terminated string for the duration of the call.
        let raw = unsafe { sys::rtcNewDevice(config.as_ptr()) };
        if raw.is_null() {
            // SAFETY: with a null device, rtcGetDeviceError reports the thread's error from
            // the failed rtcNewDevice, as documented.
            let code = unsafe { sys::rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(AccelError::Embree(format!(
                "rtcNewDevice({:?}) failed: {}",
                config,
                error_name(code)
            )));
        }
        let log: Box<ErrorLog> = Box::default();
        let user = &*log as *const ErrorLog as *mut c_void;
        // SAFETY: `raw` is a live device; `user` stays valid until `Drop` uninstalls the
        // callback, and `record_error` only reads it through a shared reference.
        unsafe { sys::rtcSetDeviceErrorFunction(raw, Some(record_error), user) };
        let device = Device { raw, log };
        device.check("rtcSetDeviceErrorFunction")?;
        // The library loaded at run time (LD_LIBRARY_PATH can swap it) must be the release whose
        // headers the bindings come from: the structs we pass differ between releases.
        // SAFETY: `raw` is a live device and RTC_DEVICE_PROPERTY_VERSION a valid property.
        let linked = unsafe { sys::rtcGetDeviceProperty(raw, sys::RTC_DEVICE_PROPERTY_VERSION) };
        device.check("rtcGetDeviceProperty(RTC_DEVICE_PROPERTY_VERSION)")?;
        let linked = i64::try_from(linked).unwrap_or(-1);
        if linked != i64::from(sys::RTC_VERSION) {
            return Err(AccelError::Embree(format!(
                "the Embree library loaded is version {}.{}.{}, but photonmap was built against \
                 the headers of Embree {}: rebuild it against the library's headers",
                linked / 10000,
                linked / 100 % 100,
                linked % 100,
                super::version()
            )));
        }
        Ok(device)
    }

    /// The raw handle, valid as long as `self` lives.
    pub fn raw(&self) -> sys::RTCDevice {
        self.raw
    }

    /// Fails if Embree reported an error since the last check, either through
    /// `rtcGetDeviceError` (this thread's first error) or through the callback (any thread).
    pub fn check(&self, what: &str) -> Result<(), AccelError> {
        // SAFETY: `self.raw` is a live device; the call also clears this thread's error code.
        let code = unsafe { sys::rtcGetDeviceError(self.raw) };
        let messages = std::mem::take(&mut *self.log.lock().unwrap_or_else(|e| e.into_inner()));
        if code == sys::RTC_ERROR_NONE && messages.is_empty() {
            return Ok(());
        }
        let mut text = format!("{what}: {}", error_name(code));
        if !messages.is_empty() {
            text.push_str(": ");
            text.push_str(&messages.join("; "));
        }
        Err(AccelError::Embree(text))
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: `self.raw` is live. The callback is removed first so that Embree can no
        // longer reach `self.log` once the box is freed; scenes that used this device hold an
        // `Arc<Device>`, so all of them have been released already.
        unsafe {
            sys::rtcSetDeviceErrorFunction(self.raw, None, std::ptr::null_mut());
            sys::rtcReleaseDevice(self.raw);
        }
    }
}
