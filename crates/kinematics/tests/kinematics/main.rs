//! Tests of the kinematics crate on the shipped robots' geometry.

mod bounded;
mod fk;
mod ik_arm;
mod ik_leg;
mod robots;
mod spatial;
mod spec;
mod urdf;

#[global_allocator]
static GLOBAL: servobus_alloc_count::Counting = servobus_alloc_count::Counting;
