//! Counts (and prints) every message of the Khronos validation layer, so a
//! run with `--validate` can end with `validation messages: N` and fail.

use ash::vk;
use std::ffi::CStr;
use std::sync::atomic::{AtomicU64, Ordering};

static MESSAGES: AtomicU64 = AtomicU64::new(0);

/// Validation messages (warnings and errors) seen since the process started.
pub fn message_count() -> u64 {
    MESSAGES.load(Ordering::SeqCst)
}

pub fn messenger_info() -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(on_message))
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut std::ffi::c_void,
) -> vk::Bool32 {
    // The loader's own chatter (e.g. about other ICDs on the machine) is not
    // a validation message of this program.
    if kind == vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
        && severity != vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
    {
        return vk::FALSE;
    }
    // SAFETY: the layer passes a valid callback-data pointer whose message is
    // a NUL-terminated string alive for the duration of this call.
    let message = unsafe {
        data.as_ref()
            .and_then(|d| d.message_as_c_str())
            .map(CStr::to_string_lossy)
            .unwrap_or_default()
    };
    MESSAGES.fetch_add(1, Ordering::SeqCst);
    eprintln!("[validation {severity:?}] {message}");
    vk::FALSE
}
