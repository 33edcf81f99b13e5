/* The one output policy (tools/common/output_guard.h) through every command that writes: no
 * output may replace one of the command's inputs (the container, the scene, its buffer and its
 * image, the plan, a part; by another name too: a hard link, a symlink, `./s/../s/`), nor a
 * device, FIFO or directory. Each case runs `lbk` ($LBK) and wants exit 2 and the victim
 * unchanged: the same bytes, or still a FIFO / character device. The character device is made
 * with mknod in the test's own folder (as root; without root that case is skipped, counted so);
 * no real device is ever named. liblbk's own atomic writer refuses a FIFO too. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include "lbk/container.h"
#include "support/scenes_dir.h"

#define SCENE "s/cornellBox-2.80-Eevee-gltf.gltf"
#define BUFFER "s/cornellBox-2.80-Eevee-gltf.bin"
#define IMAGE "s/checkerBJS.png"

static char lbk[4096], dir[] = "/tmp/lbk-output-policy-XXXXXX";
static int have_chr;

/* Runs `lbk ARGS` in the test folder; returns its exit status (-1: did not exit). */
static int run(const char *args)
{
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "cd '%s' && '%s' %s >>log.txt 2>&1 </dev/null", dir, lbk, args);
    int st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

/* The victim's identity: its bytes' hash and its kind. */
typedef struct victim {
    mode_t kind;
    unsigned long long hash, size;
} victim;

static victim look(const char *name)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    victim v = {0, 0, 0};
    struct stat st;
    if (lstat(path, &st) != 0) return v;
    v.kind = st.st_mode & S_IFMT;
    if (!S_ISREG(st.st_mode)) return v;
    FILE *f = fopen(path, "rb");
    unsigned long long h = 1469598103934665603ull;
    for (int c; f && (c = fgetc(f)) != EOF; v.size++) h = (h ^ (unsigned char)c) * 1099511628211ull;
    if (f) fclose(f);
    v.hash = h;
    return v;
}

/* `lbk ARGS` must exit 2 and leave `victim` as it was. */
static void refused(const char *args, const char *victim_name)
{
    victim before = look(victim_name);
    assert_int_not_equal(before.kind, 0);
    int rc = run(args);
    victim after = look(victim_name);
    if (rc != 2 || after.kind != before.kind || after.hash != before.hash || after.size != before.size) {
        print_error("lbk %s: exit %d (want 2); %s %s\n", args, rc, victim_name,
                    after.kind != before.kind ? "changed kind" : after.hash != before.hash ? "changed bytes" : "kept");
        fail();
    }
}

static int setup(void **state)
{
    (void)state;
    const char *l = getenv("LBK");
    if (!l || !realpath(l, lbk)) {
        const char *b = getenv("BUILD");
        snprintf(lbk, sizeof lbk, "%s/lbk", b && *b ? b : "build");
        char abs[4096];
        if (!realpath(lbk, abs)) return 0; /* each case then fails naming the missing binary */
        snprintf(lbk, sizeof lbk, "%s", abs);
    }
    if (!mkdtemp(dir)) return -1;
    char src[1024], cmd[8192];
    sd_path(src, sizeof src, "cornell_box_bjs");
    if (!sd_present(src)) return -1;
    snprintf(cmd, sizeof cmd, "cp -r '%s' '%s/s' && cd '%s' && ln s/checkerBJS.png hard.png && ln -s %s sym.bin && "
             "mkfifo fifo && mkdir folder",
             src, dir, dir, BUFFER);
    if (system(cmd) != 0) return -1;
    char chr[4200];
    snprintf(chr, sizeof chr, "%s/chr", dir);
    have_chr = geteuid() == 0 && mknod(chr, S_IFCHR | 0644, makedev(1, 3)) == 0; /* what /dev/null is */
    /* a container, a plan and its parts to refuse as outputs */
    if (run("bake " SCENE " -o a.lbk -q --samples 8 --target-error none") != 0 ||
        run("plan " SCENE " -o m.lbk --plan p.json --units 2 --samples 8 --target-error none") != 0 ||
        run("bake-unit p.json 0 -o u0.part -q") != 0 || run("bake-unit p.json 1 -o u1.part -q") != 0)
        return -1;
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static void bake_refuses_its_inputs(void **state)
{
    (void)state;
    refused("bake " SCENE " -o " SCENE " -q --samples 8", SCENE);
    refused("bake " SCENE " -o " BUFFER " -q --samples 8", BUFFER);
    refused("bake " SCENE " -o " IMAGE " -q --samples 8", IMAGE);
    refused("bake " SCENE " -o hard.png -q --samples 8", IMAGE);
    refused("bake " SCENE " -o sym.bin -q --samples 8", BUFFER);
    refused("bake ./s/../" SCENE " -o ./s/../" SCENE " -q --samples 8", SCENE);
    refused("bake " SCENE " -o b.lbk --json-report " BUFFER " -q --samples 8", BUFFER);
}

static void plan_unit_merge_refuse_their_inputs(void **state)
{
    (void)state;
    refused("plan " SCENE " -o m.lbk --plan " IMAGE " --units 2 --samples 8 --target-error none", IMAGE);
    refused("plan " SCENE " -o m.lbk --plan p2.json --makefile " BUFFER " --units 2 --samples 8 --target-error none", BUFFER);
    refused("plan " SCENE " -o " SCENE " --plan p2.json --units 2 --samples 8 --target-error none", SCENE);
    refused("bake-unit p.json 0 -o p.json", "p.json");
    refused("bake-unit p.json 0 -o " BUFFER, BUFFER);
    refused("merge p.json u0.part u1.part -o u1.part", "u1.part");
    refused("merge p.json u0.part u1.part -o m.lbk --json-report " SCENE, SCENE);
}

static void readers_refuse_their_inputs(void **state)
{
    (void)state;
    refused("convert a.lbk -o a.lbk --profile console-current", "a.lbk");
    refused("render " SCENE " a.lbk -o a.lbk", "a.lbk");
    refused("render " SCENE " a.lbk -o v.exr --png " IMAGE, IMAGE);
    refused("export a.lbk --gltf a.lbk --scene " SCENE, "a.lbk");
    refused("export a.lbk --gltf " SCENE " --scene " SCENE, SCENE);
    refused("export a.lbk --gltf " BUFFER " --scene " SCENE, BUFFER);
    /* the viewer's page would put its level.glb over the scene's */
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s/vd' && cp '%s/room_with_doors/room.glb' '%s/vd/level.glb'", dir, sd_dir(), dir);
    assert_int_equal(system(cmd), 0);
    refused("view a.lbk vd/level.glb --out vd -q", "vd/level.glb");
}

/* Every command that writes, at a FIFO, a character device and a folder. */
static void no_command_replaces_a_non_regular_file(void **state)
{
    (void)state;
    const char *targets[] = {"fifo", "chr", "folder"};
    for (int t = 0; t < 3; t++) {
        if (t == 1 && !have_chr) continue;
        const char *o = targets[t];
        char args[1024];
#define REFUSED(...) (snprintf(args, sizeof args, __VA_ARGS__), refused(args, o))
        REFUSED("bake " SCENE " -o %s -q --samples 8", o);
        REFUSED("bake " SCENE " -o b.lbk --json-report %s -q --samples 8", o);
        REFUSED("plan " SCENE " -o m.lbk --plan %s --units 2 --samples 8 --target-error none", o);
        REFUSED("bake-unit p.json 0 -o %s", o);
        REFUSED("merge p.json u0.part u1.part -o %s", o);
        REFUSED("convert a.lbk -o %s --profile console-current", o);
        REFUSED("render " SCENE " a.lbk -o %s", o);
        REFUSED("export a.lbk --gltf %s --scene " SCENE, o);
        if (t != 2) {
            REFUSED("export a.lbk --png %s", o);
            REFUSED("view a.lbk " SCENE " --out %s -q", o);
            REFUSED("diff a.lbk a.lbk --heatmap %s", o);
        }
#undef REFUSED
    }
    if (!have_chr) {
        print_message("SKIPPED: the character-device cases need root (mknod)\n");
        skip();
    }
}

/* liblbk's writer itself: a FIFO at the path is refused, not replaced by a file. */
static void library_writer_refuses_a_fifo(void **state)
{
    (void)state;
    lbk_writer *w = NULL;
    assert_int_equal(lbk_writer_open(NULL, &w), LBK_OK);
    char path[4200];
    snprintf(path, sizeof path, "%s/fifo", dir);
    assert_int_equal(lbk_writer_to_file(w, path), LBK_ERR_INVALID_ARGUMENT);
    lbk_writer_close(w);
    struct stat st;
    assert_int_equal(lstat(path, &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(bake_refuses_its_inputs),
        cmocka_unit_test(plan_unit_merge_refuse_their_inputs),
        cmocka_unit_test(readers_refuse_their_inputs),
        cmocka_unit_test(no_command_replaces_a_non_regular_file),
        cmocka_unit_test(library_writer_refuses_a_fifo),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
