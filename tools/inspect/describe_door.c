/* DOOR in `lbk inspect`: doors and combination states. CPU-only: the doors' light lives in DLS
 * sets; this section only says which sets a door state weights. */
#include <stdio.h>

#include "tools/inspect/describe.h"
#include "lbk/door.h"

void inspect_describe_door(const uint8_t *data, size_t size, inspect_stats *out)
{
    lbk_door_view *v;
    if (lbk_door_open(data, size, NULL, &v) != LBK_OK) return;
    out->parsed = 1;
    out->doors = lbk_door_count(v);
    out->door_states = lbk_door_state_count(v);
    snprintf(out->detail, sizeof out->detail, "%llu doors, %llu combination states", (unsigned long long)out->doors,
             (unsigned long long)out->door_states);
    lbk_door_close(v);
}
