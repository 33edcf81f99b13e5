/* The bake options of `lbk bake` (and of lbk plan, whose plan lbk bake-unit and lbk merge read
 * back): one table. Each row names the option, its kind, its range, its default, where it goes
 * (a field of lbk_bake_desc or of bake_args) and its help. `lbk bake --help`, the parser, the
 * range checks, cli_bake_flag and the options a plan leaves out are all read from it; docs/cli.md
 * is written from --help (tools/gen_cli_doc.sh). */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/bake_options.h"
#include "cli/cli.h"
#include "cli/options.h"
#include "lbk/bake.h"

/* What the parser fills: the arguments and -q. */
typedef struct parse_state {
    bake_args o;
    int quiet;
} parse_state;

typedef enum opt_kind {
    OPT_FLAG,   /* no value: sets its int field to 1 */
    OPT_UINT,   /* a whole number in [umin, umax] */
    OPT_NUMBER, /* a number in [min, max] ((min, max] with min_open) */
    OPT_ENUM,   /* one of choices */
    OPT_STRING, /* any text */
    OPT_HELP    /* prints the help */
} opt_kind;

typedef enum opt_field { F_NONE, F_INT, F_UNSIGNED, F_U64, F_FLOAT, F_DOUBLE, F_STR } opt_field;

enum {
    OPT_PLAN_NEUTRAL = 1, /* changes no byte of the container: a plan leaves it out (cmd_dist.c) */
    OPT_CLI_DEFAULT = 2   /* the CLI sets `def` itself before parsing (else the library's default) */
};

typedef struct opt_choice {
    const char *name;
    int value;
} opt_choice;

typedef struct bake_option bake_option;
/* An option's own store, after the table's checks (NULL: into the field). 0 or an exit code. */
typedef int (*opt_set_fn)(const bake_option *opt, const char *arg, const char *value, double number, parse_state *s);

struct bake_option {
    const char *name, *alias;      /* "--output", "-o" */
    opt_kind kind;
    opt_field field;
    size_t off;                    /* of the field in parse_state */
    const char *metavar;           /* help: the value ("FILE"); enums: their choices joined by | */
    unsigned long long umin, umax; /* OPT_UINT */
    double min, max;               /* OPT_NUMBER */
    int min_open;                  /* OPT_NUMBER: min itself is out */
    const opt_choice *choices;     /* OPT_ENUM, ending with {NULL} */
    const char *what;              /* OPT_ENUM: "unknown WHAT 'v' (a, b)"; NULL: "NAME: 'v' is not a or b" */
    const char *keyword;           /* a word taken instead of a number ("none") ... */
    double keyword_value;          /* ... and the value it stores */
    const char *def;               /* the default as help shows it ({default}); NULL: none shown */
    unsigned flags;
    opt_set_fn set;
    const char *left;              /* help's left column when not "NAME METAVAR" */
    const char *help;              /* lines split by \n; {range} and {default} are filled in; NULL:
                                      shown under another option's left column */
};

#define D(m) offsetof(parse_state, o.d.m)
#define A(m) offsetof(parse_state, o.m)

static const opt_choice presets[] = {{"fast", LBK_BAKE_PRESET_FAST}, {"high", LBK_BAKE_PRESET_HIGH}, {NULL, 0}};
static const opt_choice auto_on_off[] = {{"auto", 0}, {"on", 1}, {"off", -1}, {NULL, 0}};
static const opt_choice on_off[] = {{"on", 0}, {"off", -1}, {NULL, 0}};
static const opt_choice door_methods[] = {
    {"difference", LBK_BAKE_DOOR_DIFFERENCE}, {"guided", LBK_BAKE_DOOR_GUIDED}, {NULL, 0}};
static const opt_choice denoise_modes[] = {
    {"auto", LBK_BAKE_DENOISE_AUTO}, {"on", LBK_BAKE_DENOISE_ON}, {"off", LBK_BAKE_DENOISE_OFF}, {NULL, 0}};

/* The enum fields are stored through an int. */
_Static_assert(sizeof(lbk_bake_preset) == sizeof(int) && sizeof(lbk_bake_door_method) == sizeof(int) &&
                   sizeof(lbk_bake_denoise) == sizeof(int),
               "enum fields are int-sized");

static int set_sky(const bake_option *opt, const char *arg, const char *v, double number, parse_state *s);
static int set_checkpoint(const bake_option *opt, const char *arg, const char *v, double number, parse_state *s);
static int set_dls_threshold(const bake_option *opt, const char *arg, const char *v, double number, parse_state *s);
static int set_path_check(const bake_option *opt, const char *arg, const char *v, double number, parse_state *s);

/* In the order of `lbk bake --help`. */
static const bake_option options[] = {
    {.name = "--output", .alias = "-o", .kind = OPT_STRING, .field = F_STR, .off = A(output), .metavar = "FILE",
     .flags = OPT_PLAN_NEUTRAL, .help = "container to write (atomically; nothing is written on error)"},
    {.name = "--preset", .kind = OPT_ENUM, .field = F_INT, .off = D(preset), .choices = presets, .what = "preset",
     .def = "fast", .help = "quality preset (default {default}; see README \"Presets\")"},
    {.name = "--target-error", .kind = OPT_NUMBER, .field = F_DOUBLE, .off = D(target_error), .metavar = "X|none",
     .min = 1e-6, .max = 10, .keyword = "none", .keyword_value = -1,
     .help = "stop when the estimated relative RMSE drops below X (e.g. 0.02);\n"
             "none: run every pass --samples allows (a fixed schedule)"},
    {.name = "--time-limit", .kind = OPT_NUMBER, .field = F_DOUBLE, .off = D(time_limit), .metavar = "S",
     .min = 0.001, .max = 1e7,
     .help = "one budget of S seconds for the whole bake (base, light sets,\n"
             "doors: equal shares of what is left), then write what converged"},
    {.name = "--samples", .kind = OPT_UINT, .field = F_INT, .off = D(max_samples), .metavar = "N", .umin = 1,
     .umax = 1 << 24, .help = "sample budget per receiver (overrides the preset)"},
    {.name = "--max-bounces", .kind = OPT_UINT, .field = F_INT, .off = D(max_bounces), .metavar = "N", .umin = 1,
     .umax = 1000, .help = "bounce cap before the analytic tail (overrides the preset)"},
    {.name = "--texel-density", .kind = OPT_NUMBER, .field = F_FLOAT, .off = D(texel_density), .metavar = "D",
     .min = LBK_BAKE_TEXEL_DENSITY_MIN, .min_open = 1, .max = LBK_BAKE_TEXEL_DENSITY_MAX,
     .help = "lightmap texels per metre (overrides the scene's lbk_texel_density)"},
    {.name = "--glg-spacing", .kind = OPT_NUMBER, .field = F_FLOAT, .off = D(glg_spacing), .metavar = "M",
     .min = 1e-6, .max = 1e6, .help = "global light grid spacing in metres"},
    {.name = "--sky", .kind = OPT_STRING, .metavar = "R,G,B | FILE.exr", .set = set_sky,
     .help = "sky radiance (overrides the scene's lbk_sky)"},
    {.name = "--no-glg", .kind = OPT_FLAG, .field = F_INT, .off = D(no_glg), .help = "leave out the global light grid"},
    {.name = "--glg-lighting", .kind = OPT_FLAG, .field = F_INT, .off = D(glg_lighting),
     .help = "global light grid denser where the lighting varies, coarser where it\n"
             "is smooth (a coarse probe pass first; bake/probes/PROBES.md)"},
    {.name = "--octahedral", .kind = OPT_FLAG, .field = F_INT, .off = D(octahedral_probes),
     .help = "also write a GIBS-style octahedral probe volume (OCTP, format 1.3):\n"
             "clip levels of 32^3 probes around the playable space (the level's\n"
             "centre without lbk_playable), each coarser level doubling the\n"
             "spacing, until one holds the whole level (bake/probes/PROBES.md)"},
    {.name = "--octp-levels", .kind = OPT_UINT, .field = F_INT, .off = D(octp_levels), .metavar = "N", .umin = 1,
     .umax = 3, .def = "3",
     .help = "at most N clip levels, {range} (default {default}; 1: one level over the whole\n"
             "level, its spacing growing until it fits)"},
    {.name = "--octp-spacing", .kind = OPT_NUMBER, .field = F_FLOAT, .off = D(octp_spacing), .metavar = "M",
     .min = 1e-4, .max = 1e4,
     .help = "the finest level's probe spacing in metres (default the GLG's, or\n"
             "the longest extent / 8 when finer)"},
    {.name = "--octp-clip", .kind = OPT_UINT, .field = F_INT, .off = D(octp_clip), .metavar = "N", .umin = 2,
     .umax = 32, .def = "32", .help = "probes per axis of a clip level, {range} (default {default})"},
    {.name = "--gather-limit", .kind = OPT_NUMBER, .field = F_FLOAT, .off = D(gather_limit), .metavar = "M",
     .min = 1e-4, .max = 1e6,
     .help = "final-gather rays from surfaces end after M metres and read the\n"
             "global light grid (baked first) where they hit nothing; off by\n"
             "default (bake/transport/TRANSPORT.md, measured)"},
    {.name = "--llg-connected", .kind = OPT_FLAG, .field = F_INT, .off = D(llg_connected),
     .help = "LLG props that meet end to end (touching bounding boxes, neither\n"
             "inside the other) get twice the probes per axis (seed 001)"},
    {.name = "--error-map", .kind = OPT_FLAG, .field = F_INT, .off = D(error_map),
     .help = "also write the per-texel error map (TERR, format 1.4): each lightmap\n"
             "texel's estimated relative standard error (lbk view's error mode,\n"
             "lbk export, lbk inspect); before denoising when denoised"},
    {.name = "--block-align", .kind = OPT_FLAG, .field = F_INT, .off = D(block_align),
     .help = "charts on 4-texel boundaries, so no 4x4 block of a block-compressed pack\n"
             "(lbk convert --profile console-current, handheld) holds two charts"},
    {.name = "--max-page", .kind = OPT_UINT, .field = F_INT, .off = D(max_page), .metavar = "N",
     .umin = LBK_BAKE_MAX_PAGE_MIN, .umax = LBK_BAKE_MAX_PAGE_MAX, .def = "4096",
     .help = "no lightmap page wider or taller than N texels, {range} (default\n"
             "{default}); a level gets as many pages as it fills. A triangle larger\n"
             "than a page gets a chart of its own at the density that fits; an\n"
             "object larger than a page (its charts share one) a lower density"},
    {.name = "--texel-budget", .kind = OPT_UINT, .field = F_U64, .off = D(texel_budget), .metavar = "N",
     .umin = 1024, .umax = 1ull << 34, .def = "16777216",
     .help = "lightmap texels at most (default {default}); a level asking for more\n"
             "has every density scaled by one factor (noted)"},
    {.name = "--max-probes", .kind = OPT_UINT, .field = F_UNSIGNED, .off = D(max_probes), .metavar = "N", .umin = 4,
     .umax = 1u << 28, .def = "262144",
     .help = "global light grid probe cap, {range} (default {default}); more\n"
             "coarsens the grid's spacing until it fits"},
    {.name = "--dls-threshold", .kind = OPT_NUMBER, .metavar = "X", .min = 0, .max = 1, .def = "0.01",
     .set = set_dls_threshold,
     .help = "light sets and doors store a texel/probe only where their light\n"
             "exceeds X times the mean indirect light of the texels they light\n"
             "directly (default {default}; 0 keeps every lit receiver)"},
    {.name = "--light-culling", .kind = OPT_ENUM, .field = F_INT, .off = D(light_culling), .choices = auto_on_off,
     .def = "auto",
     .help = "stochastic light culling of punctual lights (bake/transport/SLC.md;\n"
             "{default}, the default: on with more than 32 positional lights)"},
    {.name = "--light-culling-delta", .kind = OPT_NUMBER, .field = F_DOUBLE, .off = D(light_culling_delta),
     .metavar = "X", .min = 1e-9, .max = 1e6, .def = "0.1",
     .help = "culling's delta relative to the mean punctual irradiance\n"
             "(default {default}; smaller: more lights per texel, less noise)"},
    {.name = "--glossy-vpl", .kind = OPT_ENUM, .field = F_INT, .off = D(glossy_vpl), .choices = auto_on_off,
     .def = "auto",
     .help = "glossy-to-diffuse light (caustics of metal floors) through VPLs:\n"
             "photons from point and spot lights, culled stochastically and\n"
             "gathered at the texels (bake/transport/VPL.md); {default}, the default:\n"
             "on where the lights put >= 5 % of their flux into glossy surfaces\n"
             "of roughness <= 0.3"},
    {.name = "--glossy-vpl-photons", .kind = OPT_UINT, .field = F_INT, .off = D(glossy_vpl_photons), .metavar = "N",
     .umin = 1, .umax = 1 << 20, .def = "1024",
     .help = "photons per light and half in the first pass, doubling per pass\n"
             "(default {default})"},
    {.name = "--glossy-vpl-delta", .kind = OPT_NUMBER, .field = F_DOUBLE, .off = D(glossy_vpl_delta), .metavar = "X",
     .min = 1e-9, .max = 1e6, .def = "0.1",
     .help = "the VPLs' culling delta relative to their mean irradiance at the texels\n"
             "(default {default}; smaller: more VPLs per texel, less noise)"},
    {.name = "--adaptive", .kind = OPT_ENUM, .field = F_INT, .off = D(adaptive), .choices = on_off, .def = "on",
     .help = "adaptive sampling (default {default}): blocks of 64 texels or probes whose\n"
             "own estimate reached --target-error stop while the rest go on\n"
             "(bake/transport/TRANSPORT.md)"},
    {.name = "--path-check", .kind = OPT_NUMBER, .metavar = "N|off", .min = 1, .max = 1024, .keyword = "off",
     .keyword_value = -1, .def = "16", .set = set_path_check,
     .help = "trace N texels of every lightmapped object by unbiased paths after\n"
             "the passes (default {default}; a quarter more rays, at least 2048 paths\n"
             "each) and report each object's error measured against them: what the\n"
             "noise estimate cannot see (bake/transport/TRANSPORT.md, Path check);\n"
             "off: none"},
    {.name = "--door-method", .kind = OPT_ENUM, .field = F_INT, .off = D(door_method), .choices = door_methods,
     .what = "door method", .def = "difference",
     .help = "how the light through an open door is baked: differences of\n"
             "full runs (default) or the seed's guided estimator (bake/sets/SETS.md)"},
    {.name = "--denoise", .kind = OPT_ENUM, .field = F_INT, .off = D(denoise), .choices = denoise_modes,
     .what = "denoise mode", .def = "auto",
     .help = "edge-aware denoising of lightmap texels and GLG probes, guided\n"
             "by the transport's own noise estimate; {default} (the default, both\n"
             "presets) keeps it per class of the base and of each light set or\n"
             "door state only where it lowers the estimated error; on: always\n"
             "(bake/denoise/DENOISE.md)"},
    {.name = "--threads", .kind = OPT_UINT, .field = F_INT, .off = D(threads), .metavar = "N", .umin = 1,
     .umax = 1024, .flags = OPT_PLAN_NEUTRAL, .help = "worker threads (default: all cores)"},
    {.name = "--seed", .kind = OPT_UINT, .field = F_U64, .off = D(seed), .metavar = "N", .umin = 0,
     .umax = ULLONG_MAX, .def = "1", .flags = OPT_CLI_DEFAULT, .help = "random seed (default {default})"},
    {.name = "--json-report", .kind = OPT_STRING, .field = F_STR, .off = A(json_report), .metavar = "FILE",
     .flags = OPT_PLAN_NEUTRAL,
     .help = "write the error-against-time report as JSON (with each phase's\n"
             "seconds and peak RSS, a high-water mark, also per texel)"},
    {.name = "--revision", .kind = OPT_STRING, .field = F_STR, .off = D(revision), .metavar = "STR",
     .help = "revision string stored in the provenance"},
    {.name = "--timestamp", .kind = OPT_FLAG, .field = F_INT, .off = D(timestamp),
     .help = "store the bake time in the provenance (output no longer\n"
             "byte-identical across runs)"},
    {.name = "--allow-outside", .kind = OPT_STRING, .field = F_STR, .off = D(allow_outside), .metavar = "DIR",
     .help = "the scene may also read buffers/images/sky from DIR (by default\n"
             "every file it names must lie in its own folder)"},
    {.name = "--quiet", .alias = "-q", .kind = OPT_FLAG, .field = F_INT, .off = offsetof(parse_state, quiet),
     .flags = OPT_PLAN_NEUTRAL, .help = "no progress output"},
    {.name = "--checkpoint", .kind = OPT_STRING, .metavar = "DIR", .set = set_checkpoint,
     .help = "after every pass, the bake's state into DIR (atomically)"},
    {.name = "--resume", .kind = OPT_STRING, .metavar = "DIR", .set = set_checkpoint,
     .help = "continue a killed bake from its last finished pass: the result\n"
             "is byte-identical to an uninterrupted bake (same options)"},
    {.name = "--continue", .kind = OPT_STRING, .metavar = "DIR", .set = set_checkpoint,
     .help = "add passes to a finished bake's checkpoints, up to a lower\n"
             "--target-error or a larger --samples (bake/dist/DIST.md)"},
    {.name = "--plan", .kind = OPT_STRING, .field = F_STR, .off = A(plan), .metavar = "PLAN.json",
     .flags = OPT_PLAN_NEUTRAL, .left = "--plan PLAN.json --units N [--makefile FILE] [--sbatch FILE]",
     .help = "bake nothing: write the plan of a distributed bake in N units\n"
             "(same as lbk plan; needs --samples N --target-error none)"},
    {.name = "--units", .kind = OPT_UINT, .field = F_UNSIGNED, .off = A(units), .metavar = "N", .umin = 1,
     .umax = 65536, .flags = OPT_PLAN_NEUTRAL},
    {.name = "--makefile", .kind = OPT_STRING, .field = F_STR, .off = A(makefile), .metavar = "FILE",
     .flags = OPT_PLAN_NEUTRAL},
    {.name = "--sbatch", .kind = OPT_STRING, .field = F_STR, .off = A(sbatch), .metavar = "FILE",
     .flags = OPT_PLAN_NEUTRAL},
    {.name = "--help", .alias = "-h", .kind = OPT_HELP, .help = "this text"},
};
#define OPTION_COUNT (sizeof options / sizeof options[0])

#undef D
#undef A

static const bake_option *find_option(const char *arg)
{
    for (size_t i = 0; i < OPTION_COUNT; i++)
        if (!strcmp(arg, options[i].name) || (options[i].alias && !strcmp(arg, options[i].alias))) return &options[i];
    return NULL;
}

/* ---- help ---------------------------------------------------------------------------------- */

#define HELP_COLUMN 26 /* where the descriptions start; a longer left column gets its own line */

/* The range of a numeric option as the messages and the help write it. */
static void format_range(const bake_option *opt, char *out, size_t size, int dash)
{
    if (opt->kind == OPT_UINT) {
        if (dash) snprintf(out, size, "%llu-%llu", opt->umin, opt->umax);
        else snprintf(out, size, "[%llu, %llu]", opt->umin, opt->umax);
    } else {
        if (dash) snprintf(out, size, "%g-%g", opt->min, opt->max);
        else snprintf(out, size, "%c%g, %g]", opt->min_open ? '(' : '[', opt->min, opt->max);
    }
}

/* "a|b|c" */
static void join_choices(const opt_choice *c, const char *sep, const char *last_sep, char *out, size_t size)
{
    size_t n = 0;
    out[0] = 0;
    for (size_t i = 0; c[i].name && n < size; i++) {
        const char *s = i == 0 ? "" : c[i + 1].name ? sep : last_sep;
        n += (size_t)snprintf(out + n, size - n, "%s%s", s, c[i].name);
    }
}

static void print_help_text(FILE *f, const bake_option *opt)
{
    for (const char *p = opt->help; *p; p++) {
        if (*p == '\n') {
            fprintf(f, "\n%*s", HELP_COLUMN, "");
        } else if (!strncmp(p, "{range}", 7)) {
            char r[96];
            format_range(opt, r, sizeof r, 1);
            fputs(r, f);
            p += 6;
        } else if (!strncmp(p, "{default}", 9)) {
            fputs(opt->def ? opt->def : "", f);
            p += 8;
        } else {
            fputc(*p, f);
        }
    }
    fputc('\n', f);
}

static void print_options(FILE *f)
{
    for (size_t i = 0; i < OPTION_COUNT; i++) {
        const bake_option *opt = &options[i];
        if (!opt->help) continue;
        char left[160], meta[96];
        const char *mv = opt->metavar;
        if (opt->kind == OPT_ENUM) {
            join_choices(opt->choices, "|", "|", meta, sizeof meta);
            mv = meta;
        }
        if (opt->left) snprintf(left, sizeof left, "%s", opt->left);
        else
            snprintf(left, sizeof left, "%s%s%s%s%s", opt->alias ? opt->alias : "", opt->alias ? ", " : "", opt->name,
                     mv ? " " : "", mv ? mv : "");
        int w = HELP_COLUMN - 3;
        if ((int)strlen(left) <= w) fprintf(f, "  %-*s ", w, left);
        else fprintf(f, "  %s\n%*s", left, HELP_COLUMN, "");
        print_help_text(f, opt);
    }
}

static void help(FILE *f)
{
    fputs("usage: lbk bake SCENE.gltf|SCENE.glb -o OUT.lbk [options]\n"
          "\n"
          "Bakes global illumination for a glTF level into a container: AHD lightmaps, an SH9\n"
          "global light grid, local light grids for props, and dynamic light sets and doors when\n"
          "the scene has them. Same input, options and seed give byte-identical output at any\n"
          "thread count.\n"
          "\n"
          "options:\n",
          f);
    print_options(f);
    fputs("\n"
          "exit codes: 0 ok, 2 usage, 3 I/O error, 4 unusable scene, 5 internal error\n",
          f);
}

/* ---- parsing ------------------------------------------------------------------------------- */

static int parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end) return 0;
    *out = v;
    return 1;
}

static void *field_of(const bake_option *opt, parse_state *s) { return (char *)s + opt->off; }

static void store_number(const bake_option *opt, parse_state *s, double d, unsigned long long u)
{
    void *p = field_of(opt, s);
    switch (opt->field) {
    case F_INT: *(int *)p = opt->kind == OPT_UINT ? (int)u : (int)d; break;
    case F_UNSIGNED: *(unsigned *)p = (unsigned)u; break;
    case F_U64: *(uint64_t *)p = u; break;
    case F_FLOAT: *(float *)p = (float)d; break;
    case F_DOUBLE: *(double *)p = d; break;
    default: break;
    }
}

/* The choice named v, or NULL after saying which there are. */
static const opt_choice *find_choice(const bake_option *opt, const char *a, const char *v)
{
    for (const opt_choice *c = opt->choices; c->name; c++)
        if (!strcmp(c->name, v)) return c;
    char list[128];
    if (opt->what) {
        join_choices(opt->choices, ", ", ", ", list, sizeof list);
        fprintf(stderr, "lbk bake: unknown %s '%s' (%s)\n", opt->what, v, list);
    } else {
        join_choices(opt->choices, ", ", " or ", list, sizeof list);
        fprintf(stderr, "lbk bake: %s: '%s' is not %s\n", a, v, list);
    }
    return NULL;
}

/* One option and its value (NULL when the command line ended); 0 or the exit code. */
static int apply(const bake_option *opt, const char *a, const char *v, parse_state *s)
{
    double d = 0;
    unsigned long long u = 0;
    if (opt->kind == OPT_FLAG) {
        *(int *)field_of(opt, s) = 1;
        return 0;
    }
    if (!v) {
        fprintf(stderr, "lbk bake: %s needs a value\n", a);
        return LBK_EXIT_USAGE;
    }
    if (opt->kind == OPT_UINT) {
        if (!cli_parse_uint(v, opt->umin, opt->umax, &u)) {
            fprintf(stderr, "lbk bake: %s: '%s' is not a whole number in [%llu, %llu]\n", a, v, opt->umin, opt->umax);
            return LBK_EXIT_USAGE;
        }
        d = (double)u;
    } else if (opt->kind == OPT_NUMBER) {
        if (opt->keyword && !strcmp(v, opt->keyword)) {
            d = opt->keyword_value;
        } else {
            int ok = parse_double(v, &d) && (opt->min_open ? d > opt->min : d >= opt->min) && d <= opt->max;
            /* a float field must not turn a tiny value into 0 (the default) */
            if (ok && opt->field == F_FLOAT && d != 0 && (float)d == 0) ok = 0;
            if (!ok) {
                char r[96];
                format_range(opt, r, sizeof r, 0);
                fprintf(stderr, "lbk bake: %s: '%s' is not a number in %s\n", a, v, r);
                return LBK_EXIT_USAGE;
            }
        }
    } else if (opt->kind == OPT_ENUM) {
        const opt_choice *c = find_choice(opt, a, v);
        if (!c) return LBK_EXIT_USAGE;
        d = c->value;
    }
    if (opt->set) return opt->set(opt, a, v, d, s);
    if (opt->field == F_STR) *(const char **)field_of(opt, s) = v;
    else store_number(opt, s, d, u);
    return 0;
}

static int set_sky(const bake_option *opt, const char *a, const char *v, double number, parse_state *s)
{
    float r, g, b;
    char tail;
    s->o.d.sky_override = 1;
    if (sscanf(v, "%f,%f,%f%c", &r, &g, &b, &tail) == 3) {
        if (!(r >= 0 && g >= 0 && b >= 0 && r < 1e30f && g < 1e30f && b < 1e30f)) {
            fprintf(stderr, "lbk bake: --sky: radiance must be finite and >= 0\n");
            return LBK_EXIT_USAGE;
        }
        s->o.d.sky[0] = r, s->o.d.sky[1] = g, s->o.d.sky[2] = b;
    } else {
        s->o.d.sky_exr = v;
    }
    return 0;
}

static int set_checkpoint(const bake_option *opt, const char *a, const char *v, double number, parse_state *s)
{
    if (s->o.d.checkpoint_dir) {
        fprintf(stderr, "lbk bake: one of --checkpoint, --resume, --continue\n");
        return LBK_EXIT_USAGE;
    }
    s->o.d.checkpoint_dir = v;
    s->o.d.resume = strcmp(opt->name, "--checkpoint") != 0;
    s->o.continued = !strcmp(opt->name, "--continue");
    return 0;
}

/* 0 keeps every lit receiver: the desc's < 0 (its 0 is the default). */
static int set_dls_threshold(const bake_option *opt, const char *a, const char *v, double number, parse_state *s)
{
    s->o.d.dls_threshold = number > 0 ? number : -1;
    return 0;
}

static int set_path_check(const bake_option *opt, const char *a, const char *v, double number, parse_state *s)
{
    (void)opt;
    if (number != floor(number)) {
        fprintf(stderr, "lbk bake: %s: '%s' is not a whole number in [1, 1024] or off\n", a, v);
        return LBK_EXIT_USAGE;
    }
    s->o.d.path_check = (int)number;
    return 0;
}

int cli_bake_flag(const char *arg)
{
    const bake_option *opt = find_option(arg);
    return opt && (opt->kind == OPT_FLAG || opt->kind == OPT_HELP);
}

int cli_bake_plan_neutral(const char *arg)
{
    const bake_option *opt = find_option(arg);
    return opt && (opt->flags & OPT_PLAN_NEUTRAL);
}

int cli_bake_parse(int argc, char **argv, bake_args *out, int *quiet_out)
{
    parse_state s;
    memset(&s, 0, sizeof s);
    s.o.d.size = sizeof s.o.d; /* this build's fields, block_align included */
    for (size_t i = 0; i < OPTION_COUNT; i++)
        if (options[i].flags & OPT_CLI_DEFAULT) (void)apply(&options[i], options[i].name, options[i].def, &s);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const bake_option *opt = find_option(a);
        if (opt) {
            if (opt->kind == OPT_HELP) {
                help(stdout);
                return LBK_EXIT_OK;
            }
            int takes_value = opt->kind != OPT_FLAG;
            const char *v = takes_value && i + 1 < argc ? argv[i + 1] : NULL;
            int rc = apply(opt, a, v, &s);
            if (rc) return rc;
            if (takes_value) i++;
        } else if (a[0] == '-' && a[1]) {
            fprintf(stderr, "lbk bake: unknown option '%s' (lbk bake --help)\n", a);
            return LBK_EXIT_USAGE;
        } else if (!s.o.input) {
            s.o.input = a;
        } else {
            fprintf(stderr, "lbk bake: more than one input scene ('%s', '%s')\n", s.o.input, a);
            return LBK_EXIT_USAGE;
        }
    }
    *out = s.o;
    *quiet_out = s.quiet;
    return -1;
}
