/* The first tick: the configuration record (parameters, key, WiFi) from the HAL's store, a new session, and
 * the BOOT event (arg = the board's reset cause). */
#include "rw_core_internal.h"

/* First tick: the stored configuration (key, parameters) and a new session: the boot counter goes up and is
 * written back at once, so that no later boot can reuse this session id (session epoch + boot counter,
 * rw_config.h). With the counter used up the key is forgotten rather than an id reused. */
static void load_config(rw_core *core, const rw_hal *hal)
{
    rw_config *c = &core->state.config;
    bool stored = hal->config != NULL && hal->config->load(hal->config->ctx, c, sizeof *c) && rw_config_valid(c);
    if (stored) {
        for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
            if (rw_params_check(&core->params, (uint8_t)i, c->params[i], true) == RW_DECODE_OK) {
                core->params.value[i] = c->params[i];
            }
        }
        rw_core_apply_params(core);
    } else {
        rw_config_defaults(c);
        rw_config_set_params(c, core->params.value);
    }
    if (!rw_config_next_boot(c)) {
        rw_config_clear_key(c);
    }
    core->state.session_id = rw_config_session_id(c);
    rw_core_link_prepare_key(core);
    if (hal->config != NULL) {
        (void)hal->config->save(hal->config->ctx, c, sizeof *c);
    }
}

void rw_core_boot(rw_core *core, const rw_hal *hal)
{
    load_config(core, hal);
    rw_core_emit_event(core, RW_EVENT_KIND_BOOT, core->state.state, core->state.state, (int32_t)core->reset_cause);
}
