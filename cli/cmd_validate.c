/* lbk validate FILE [--json] [--quiet]: every issue of spec/validation.md with its ID,
 * severity, section and byte offset; exit 0 valid, 1 invalid, 2 usage, 3 I/O. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli/cli.h"
#include "cli/options.h"
#include "lbk/validate.h"

static const char *severity_name(lbk_severity s)
{
    return s == LBK_SEVERITY_FATAL ? "fatal" : s == LBK_SEVERITY_ERROR ? "error" : "warning";
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lbk validate FILE [--json] [--quiet] [--max-memory SIZE]\n"
            "\n"
            "Runs every check of spec/validation.md on a container and lists each issue with its\n"
            "ID, severity, section, byte offset and message, then a summary line.\n"
            "\n"
            "  --json    one JSON document (schema \"lbk-validate/1\", spec/inspect-json.md)\n"
            "  --quiet   print nothing; only the exit code tells\n"
            CLI_MAX_MEMORY_HELP
            "  --help    this text\n"
            "\n"
            "exit codes: 0 valid (warnings allowed), 1 invalid, 2 usage, 3 I/O error, 5 internal\n");
}

typedef struct validate_out {
    int json, quiet;
    cJSON *issues;
    int oom;
} validate_out;

static int on_issue(void *user, const lbk_issue *issue)
{
    validate_out *o = user;
    char cc[5] = "-";
    if (issue->section_type) lbk_fourcc_string(issue->section_type, cc);
    if (o->json) {
        cJSON *j = cJSON_CreateObject();
        if (!j || !cJSON_AddItemToArray(o->issues, j)) {
            cJSON_Delete(j);
            o->oom = 1;
            return 1;
        }
        cJSON_AddNumberToObject(j, "id", issue->id);
        cJSON_AddStringToObject(j, "severity", severity_name(issue->severity));
        if (issue->section_type) cJSON_AddStringToObject(j, "section", cc);
        else cJSON_AddNullToObject(j, "section");
        cJSON_AddNumberToObject(j, "offset", (double)issue->offset);
        cJSON_AddStringToObject(j, "message", issue->message);
    } else if (!o->quiet) {
        printf("%-7s %4u  %-4s  @%-10llu %s\n", severity_name(issue->severity), issue->id, cc,
               (unsigned long long)issue->offset, issue->message);
    }
    return 0;
}

int lbk_cmd_validate(int argc, char **argv)
{
    const char *path = NULL;
    validate_out o = {0};
    uint64_t max_memory = 0;
    for (int i = 1; i < argc; i++) {
        const int mm = cli_max_memory_option("validate", argc, argv, &i, &max_memory);
        if (mm < 0) return LBK_EXIT_USAGE;
        if (mm) continue;
        if (!strcmp(argv[i], "--json")) o.json = 1;
        else if (!strcmp(argv[i], "--quiet") || !strcmp(argv[i], "-q")) o.quiet = 1;
        else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return LBK_EXIT_OK;
        } else if (argv[i][0] == '-' && argv[i][1]) {
            fprintf(stderr, "lbk validate: unknown option '%s'\n", argv[i]);
            usage(stderr);
            return LBK_EXIT_USAGE;
        } else if (path) {
            fprintf(stderr, "lbk validate: one FILE only ('%s' and '%s')\n", path, argv[i]);
            return LBK_EXIT_USAGE;
        } else {
            path = argv[i];
        }
    }
    if (!path) {
        usage(stderr);
        return LBK_EXIT_USAGE;
    }
    if (o.json && o.quiet) o.json = 0; /* quiet wins: nothing is printed */
    cJSON *doc = NULL;
    if (o.json) {
        doc = cJSON_CreateObject();
        if (doc) {
            cJSON_AddStringToObject(doc, "schema", "lbk-validate/1");
            cJSON_AddStringToObject(doc, "file", path);
        }
        o.issues = doc ? cJSON_AddArrayToObject(doc, "issues") : NULL;
        if (!o.issues) {
            cJSON_Delete(doc);
            fprintf(stderr, "lbk validate: out of memory\n");
            return LBK_EXIT_INTERNAL;
        }
    }
    lbk_validate_summary s;
    errno = 0;
    lbk_validate_options vo = LBK_VALIDATE_OPTIONS_INIT;
    vo.max_decoded_bytes = max_memory;
    lbk_result r = lbk_validate_file(path, &vo, on_issue, &o, &s);
    if (r == LBK_ERR_IO || r == LBK_ERR_LIMIT) {
        if (!o.quiet) fprintf(stderr, "lbk validate: %s: %s\n", path, errno ? strerror(errno) : lbk_result_message(r));
        cJSON_Delete(doc);
        return LBK_EXIT_IO;
    }
    if (r != LBK_OK || o.oom) {
        if (!o.quiet) fprintf(stderr, "lbk validate: %s: %s\n", path, o.oom ? "out of memory" : lbk_result_message(r));
        cJSON_Delete(doc);
        return LBK_EXIT_INTERNAL;
    }
    const int valid = s.fatal == 0 && s.errors == 0;
    if (o.json) {
        cJSON_AddBoolToObject(doc, "valid", valid);
        cJSON *sum = cJSON_AddObjectToObject(doc, "summary");
        if (sum) {
            cJSON_AddNumberToObject(sum, "fatal", s.fatal);
            cJSON_AddNumberToObject(sum, "errors", s.errors);
            cJSON_AddNumberToObject(sum, "warnings", s.warnings);
        }
        char *text = cJSON_Print(doc);
        if (!text) {
            cJSON_Delete(doc);
            fprintf(stderr, "lbk validate: out of memory\n");
            return LBK_EXIT_INTERNAL;
        }
        puts(text);
        cJSON_free(text);
        cJSON_Delete(doc);
    } else if (!o.quiet) {
        printf("%s: %s (%u fatal, %u error%s, %u warning%s)\n", path, valid ? "valid" : "INVALID", s.fatal, s.errors,
               s.errors == 1 ? "" : "s", s.warnings, s.warnings == 1 ? "" : "s");
    }
    return valid ? LBK_EXIT_OK : LBK_EXIT_NEGATIVE;
}
