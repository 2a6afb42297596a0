#include "rw_link_status.h"

#include "rw_wifi_supervisor.h"

bool rw_link_status_led_on(uint32_t now_ms, uint8_t state)
{
    switch (state) {
    case RW_WIFI_NOT_PROVISIONED: {
        const uint32_t t = now_ms % 2000u;
        return t < 100u || (t >= 300u && t < 400u);
    }
    case RW_WIFI_NO_MODULE:
        return true;
    case RW_WIFI_CONNECTING:
        return (now_ms % 200u) < 100u;
    case RW_WIFI_UP:
    default:
        return (now_ms % 1000u) < 50u;
    }
}

const char *rw_link_status_text(uint8_t state)
{
    switch (state) {
    case RW_WIFI_NOT_PROVISIONED:
        return "wifi NOT_PROVISIONED: no SSID stored (provision over USB)";
    case RW_WIFI_NO_MODULE:
        return "wifi NO_MODULE: the NINA WiFi module does not answer (LED steady on); reset or check the module";
    case RW_WIFI_CONNECTING:
        return "wifi CONNECTING";
    case RW_WIFI_UP:
        return "wifi UP";
    default:
        return "wifi ?";
    }
}
