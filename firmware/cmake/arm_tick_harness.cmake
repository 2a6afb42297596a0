# Included by firmware/CMakeLists.txt when cross-compiling (arm-none-eabi.cmake): the bare-metal tick
# harness ELF that links the core for the SAMD21G18A memory map, so its size is real and an emulator
# can count the instructions of one control tick.
set_target_properties(rw_core PROPERTIES POSITION_INDEPENDENT_CODE OFF)

add_executable(rw_arm_tick_harness ${CMAKE_CURRENT_LIST_DIR}/arm_tick_harness.c)
set_target_properties(rw_arm_tick_harness PROPERTIES SUFFIX ".elf" POSITION_INDEPENDENT_CODE OFF)
target_link_libraries(rw_arm_tick_harness PRIVATE rw_core)
target_compile_options(rw_arm_tick_harness PRIVATE ${RW_WARNINGS})
target_link_options(rw_arm_tick_harness PRIVATE
    -nostartfiles
    # entry points only the emulator calls: roots for --gc-sections
    -Wl,--undefined=harness_state -Wl,--undefined=harness_set_clock -Wl,--undefined=harness_init
    -Wl,--undefined=harness_session_id -Wl,--undefined=harness_test_key -Wl,--undefined=rw_siphash24
    -T${CMAKE_CURRENT_LIST_DIR}/samd21g18a.ld
    -Wl,-Map=${CMAKE_CURRENT_BINARY_DIR}/rw_arm_tick_harness.map
    -Wl,--print-memory-usage)
set_target_properties(rw_arm_tick_harness PROPERTIES LINK_DEPENDS ${CMAKE_CURRENT_LIST_DIR}/samd21g18a.ld)
add_custom_command(TARGET rw_arm_tick_harness POST_BUILD
    COMMAND ${CMAKE_SIZE} -A $<TARGET_FILE:rw_arm_tick_harness> > ${CMAKE_CURRENT_BINARY_DIR}/rw_arm_tick_harness.size.txt
    VERBATIM)
