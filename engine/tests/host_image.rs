//! Host-written images (`backend::host_image`): an array element is lent
//! to one writer at a time, only host-written images lend, and a level is
//! handed out only at its own size. (That the texels land where frames
//! sample them is `map_prefetch.rs`: maps decoded into slots play the
//! frames staging uploads play, bit for bit.)

mod common;

use ash::vk;
use engine::backend::host_image::HostElement;
use engine::backend::{Image, ImageDesc};
use std::sync::Arc;

fn cube_array(host: bool) -> ImageDesc {
    let desc = ImageDesc::new_cube_array(vk::Format::R16G16B16A16_SFLOAT, 16, 3)
        .all_mip_levels()
        .usage(vk::ImageUsageFlags::SAMPLED);
    if host { desc.host_written() } else { desc }
}

#[test]
fn an_element_has_one_writer_at_a_time() {
    let device = common::validated_device();
    assert!(
        Image::host_writable(&device, cube_array(true)),
        "lavapipe samples linear cube arrays"
    );
    let image = Arc::new(Image::new(&device, "host cube array", cube_array(true)).expect("image"));
    let mut first = HostElement::lend(&image, 1).expect("element 1");
    assert!(HostElement::lend(&image, 1).is_err(), "lent twice");
    let other = HostElement::lend(&image, 2).expect("another element");
    assert!(
        HostElement::lend(&image, 3).is_err(),
        "past the last element"
    );
    // A level only at its own tight size; 16² RGBA16F = 2048 bytes.
    assert!(first.level_mut(0, 0, 2048).is_some());
    assert!(first.level_mut(0, 0, 2040).is_none());
    assert!(
        first.level_mut(6, 0, 2048).is_none(),
        "a cube has six faces"
    );
    // The 1×1 level's row is padded: written through scratch.
    assert!(first.level_mut(5, 4, 8).is_some_and(|b| b.len() == 8));
    drop(first);
    let again = HostElement::lend(&image, 1).expect("given back on drop");
    assert_eq!((again.element(), other.element()), (1, 2));

    let plain =
        Arc::new(Image::new(&device, "plain cube array", cube_array(false)).expect("image"));
    assert!(HostElement::lend(&plain, 0).is_err(), "not host-written");
    drop((again, other, image, plain));
    common::assert_no_validation_messages();
}
