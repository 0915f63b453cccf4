/*
 * test_skeleton_swc.c — the SWC reader (bake/skeleton_swc.c): valid files
 * (comments, blank lines, CRLF, sparse unsorted ids, forward parents, the
 * bundled data), each malformed case with its issue code and the line named
 * in the message, the text format's twist= field, and truncated / mutated inputs that must never crash.
 */
#include <string.h>

#include "skeleton_swc.h"
#include "test_util.h"

static meso_result parse(const char* text, meso_skeleton* s, meso_error* err)
{
    memset(err, 0, sizeof(*err));
    return meso_skeleton_parse_swc(text, strlen(text), s, err);
}

static void test_valid(void)
{
    const char* text = "# comment\n"
                       "\n"
                       "  10 1 0 0 0 2.5 -1   # root\r\n"
                       "7 3 1e0 0 0 1 30\n"  /* parent defined later */
                       "30 3 0.5 0 0 1.5 10\r"
                       "\t\n"
                       "8 3 0 1 0 0 30";     /* no final newline, zero radius */
    meso_skeleton s;
    meso_error err;
    assert(parse(text, &s, &err) == MESO_OK);
    assert(s.node_count == 4 && s.root_count == 1);
    assert(s.nodes[0].id == 10 && s.nodes[0].parent == -1 && s.nodes[0].line == 3);
    assert(s.nodes[0].radius == 2.5 && s.nodes[0].type == 1);
    assert(s.nodes[1].id == 7 && s.nodes[1].parent == 2 && s.nodes[1].line == 4 && s.nodes[1].pos[0] == 1.0);
    assert(s.nodes[2].id == 30 && s.nodes[2].parent == 0 && s.nodes[2].line == 5);
    assert(s.nodes[3].id == 8 && s.nodes[3].parent == 2 && s.nodes[3].line == 7);
    assert(s.nodes[2].child_count == 2);
    assert(s.children[s.nodes[2].first_child] == 1 && s.children[s.nodes[2].first_child + 1] == 3);
    assert(s.nodes[0].child_count == 1 && s.children[s.nodes[0].first_child] == 2);
    meso_skeleton_free(&s);
    meso_skeleton_free(&s); /* idempotent */
    meso_skeleton_free(NULL);
}

static void test_files(void)
{
    const char* names[] = {"morphio_soma_single_frustum.swc", "neurom_simple.swc", "neurom_fat_end.swc"};
    const uint32_t counts[] = {2, 9, 10};
    for (int i = 0; i < 3; ++i) {
        meso_skeleton s;
        meso_error err;
        meso_result r = meso_skeleton_load_swc(test_data(names[i]), &s, &err);
        if (r != MESO_OK)
            fprintf(stderr, "%s: %s\n", names[i], err.message);
        assert(r == MESO_OK && s.node_count == counts[i] && s.root_count == 1);
        meso_skeleton_free(&s);
    }
    meso_skeleton s;
    meso_error err;
    assert(meso_skeleton_load_swc("/nonexistent/x.swc", &s, &err) == MESO_ERR_IO);
    assert(err.code == MESO_SKEL_ISSUE_UNREADABLE && strstr(err.message, "/nonexistent/x.swc"));
}

typedef struct bad_case {
    const char* text;
    uint32_t code;
    const char* needle; /* must appear in the message: the line and the problem */
    const char* needle2;
} bad_case;

static void test_errors(void)
{
    const bad_case cases[] = {
        {"", MESO_SKEL_ISSUE_EMPTY, "no node", NULL},
        {"# only a comment\n\n   \n", MESO_SKEL_ISSUE_EMPTY, "no node", NULL},
        {"1 1 0 0 0 1 -1\n2 1 0 0 1 -1\n", MESO_SKEL_ISSUE_FIELD_COUNT, "line 2", "6 fields"},
        {"1 1 0 0 0 1 -1 5\n", MESO_SKEL_ISSUE_FIELD_COUNT, "line 1", "8 fields"},
        {"1 1 0 0 0 1 -1\n\n2 1 0 zero 0 1 1\n", MESO_SKEL_ISSUE_NOT_A_NUMBER, "line 3", "y 'zero'"},
        {"1 1 0 0 0 1 -1\n2.5 1 0 0 0 1 1\n", MESO_SKEL_ISSUE_NOT_A_NUMBER, "line 2", "id '2.5'"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 0 1 1x\n", MESO_SKEL_ISSUE_NOT_A_NUMBER, "line 2", "parent"},
        {"1 1 0 0 0 1 -1\n2 a 0 0 0 1 1\n", MESO_SKEL_ISSUE_NOT_A_NUMBER, "line 2", "type"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 0 1 99999999999999999999999\n", MESO_SKEL_ISSUE_NOT_A_NUMBER, "line 2", "parent"},
        {"1 1 nan 0 0 1 -1\n", MESO_SKEL_ISSUE_NON_FINITE, "line 1", "x 'nan'"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 inf 1 1\n", MESO_SKEL_ISSUE_NON_FINITE, "line 2", "z"},
        {"1 1 0 0 0 1e999 -1\n", MESO_SKEL_ISSUE_NON_FINITE, "line 1", "radius"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 1 -0.5 1\n", MESO_SKEL_ISSUE_NEGATIVE_RADIUS, "line 2", "negative radius"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 1 1 1\n1 1 0 1 1 1 2\n", MESO_SKEL_ISSUE_DUPLICATE_ID, "line 3", "line 1"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 1 1 7\n", MESO_SKEL_ISSUE_UNKNOWN_PARENT, "line 2", "parent 7"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 1 1 -2\n", MESO_SKEL_ISSUE_UNKNOWN_PARENT, "line 2", "-2"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 1 1 3\n3 1 0 0 2 1 4\n4 1 0 0 3 1 2\n", MESO_SKEL_ISSUE_CYCLE, "line", "cycle"},
        {"5 1 0 0 0 1 5\n", MESO_SKEL_ISSUE_CYCLE, "line 1", "own ancestor"},
        {"1 1 1e300 0 0 1 -1\n2 1 0 1 0 1 1\n", MESO_SKEL_ISSUE_OUT_OF_RANGE, "line 1", "x 1e+300"},
        {"1 1 0 0 0 1 -1\n2 1 0 -1.000001e15 0 1 1\n", MESO_SKEL_ISSUE_OUT_OF_RANGE, "line 2", "y"},
        {"1 1 0 0 0 2e15 -1\n", MESO_SKEL_ISSUE_OUT_OF_RANGE, "line 1", "radius"},
        {"1 1 0 0 0 1 -1\n2 1 0 0 0\0 1 1\n", MESO_SKEL_ISSUE_NOT_A_NUMBER, "line 2", NULL},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); ++i) {
        meso_skeleton s;
        meso_error err;
        size_t len = strlen(cases[i].text);
        if (i + 1 == sizeof(cases) / sizeof(cases[0]))
            len = sizeof("1 1 0 0 0 1 -1\n2 1 0 0 0\0 1 1\n") - 1; /* the embedded NUL is data */
        memset(&err, 0, sizeof(err));
        meso_result r = meso_skeleton_parse_swc(cases[i].text, len, &s, &err);
        fprintf(stderr, "    E%u %s\n", err.code, err.message);
        assert(r == MESO_ERR_CORRUPT);
        assert(err.code == cases[i].code);
        assert(strstr(err.message, cases[i].needle));
        assert(!cases[i].needle2 || strstr(err.message, cases[i].needle2));
        assert(s.node_count == 0 && s.nodes == NULL && s.children == NULL);
    }
    meso_skeleton s;
    meso_error err;
    assert(meso_skeleton_parse_swc(NULL, 1, &s, &err) == MESO_ERR_INVALID_ARG);
    assert(meso_skeleton_parse_swc("x", 1, NULL, &err) == MESO_ERR_INVALID_ARG);
}

/* Parsed but nothing to draw (meso_skeleton_require_drawable), in both
 * formats; the largest accepted magnitude (1e15) parses and draws. */
static void test_drawable(void)
{
    static const struct {
        meso_skeleton_format fmt;
        const char* text;
        uint32_t code; /* 0: drawable */
    } cases[] = {
        {MESO_SKELETON_SWC, "1 1 0 0 0 1 -1\n", MESO_SKEL_ISSUE_NO_SEGMENT},
        {MESO_SKELETON_SWC, "1 1 0 0 0 1 -1\n2 1 5 0 0 1 -1\n", MESO_SKEL_ISSUE_NO_SEGMENT},
        {MESO_SKELETON_SWC, "1 1 0 0 0 0 -1\n2 3 0 1 0 0 1\n3 3 0 2 0 0 2\n", MESO_SKEL_ISSUE_NO_RADIUS},
        {MESO_SKELETON_SWC, "1 1 0 0 0 1 -1\n2 3 0 0 0 1 1\n", MESO_SKEL_ISSUE_NO_SURFACE},
        {MESO_SKELETON_SWC, "1 1 0 0 0 1 -1\n2 3 0 0 0 1 1\n3 3 0 0 1 0 -1\n4 3 0 0 2 0 3\n",
            MESO_SKEL_ISSUE_NO_SURFACE},
        {MESO_SKELETON_SWC, "1 1 0 0 0 0 -1\n2 3 0 1 0 0.5 1\n", 0},
        {MESO_SKELETON_SWC, "1 1 -1e15 0 0 1e15 -1\n2 3 1e15 0 0 1 1\n", 0},
        {MESO_SKELETON_TEXT, "0 0 0 1\n", MESO_SKEL_ISSUE_NO_SEGMENT},
        {MESO_SKELETON_TEXT, "0 0 0 0\n0 1 0 0\n", MESO_SKEL_ISSUE_NO_RADIUS},
        {MESO_SKELETON_TEXT, "0 0 0 1\n0 0 0 1\n", MESO_SKEL_ISSUE_NO_SURFACE},
        {MESO_SKELETON_TEXT, "0 0 0 1\n0 1 0 0\n", 0},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); ++i) {
        meso_skeleton s;
        meso_error err;
        memset(&err, 0, sizeof(err));
        assert(meso_skeleton_parse(cases[i].text, strlen(cases[i].text), cases[i].fmt, &s, &err) == MESO_OK);
        memset(&err, 0, sizeof(err));
        const meso_result r = meso_skeleton_require_drawable(&s, &err);
        fprintf(stderr, "    case %zu: E%u %s\n", i, err.code, err.message);
        assert(r == (cases[i].code ? MESO_ERR_CORRUPT : MESO_OK));
        assert(err.code == cases[i].code);
        assert(!cases[i].code || strstr(err.message, "line"));
        meso_skeleton_free(&s);
    }
}

/* Every prefix of a valid file, and many single-byte mutations: either a
 * skeleton or a coded error, never a crash (ASan/UBSan build). */
static void test_mutations(void)
{
    static const char base[] = "# fuzz seed\n1 1 0 0 0 3.0 -1\n2 3 0 0 2 0.5 1\n3 3 0 0 2 0.5 2\n"
                               "4 3 0 1e1 3 0.5 3\r\n5 3 0 0 4 0.5 4\n6 3 -1.5e-3 0 5 13. 5\n";
    size_t n = sizeof(base) - 1;
    char* buf = malloc(n + 1);
    assert(buf);
    uint32_t ok = 0, bad = 0;
    for (size_t len = 0; len <= n; ++len) {
        memcpy(buf, base, len); /* exactly len bytes: reads beyond are ASan errors */
        meso_skeleton s;
        meso_error err;
        memset(&err, 0, sizeof(err));
        meso_result r = meso_skeleton_parse_swc(buf, len, &s, &err);
        if (r == MESO_OK)
            ++ok;
        else {
            ++bad;
            assert((err.code >= MESO_SKEL_ISSUE_EMPTY && err.code <= MESO_SKEL_ISSUE_UNREADABLE) ||
                   err.code == MESO_SKEL_ISSUE_OUT_OF_RANGE);
        }
        meso_skeleton_free(&s);
    }
    const char alphabet[] = "0123456789-+.eE #\n\r\t nanifx\0\xff";
    uint64_t rng = 0x5eed5eedULL;
    for (int it = 0; it < 4000; ++it) {
        memcpy(buf, base, n);
        int muts = 1 + (int)(test_rng_next(&rng) % 4);
        for (int k = 0; k < muts; ++k) {
            size_t at = (size_t)(test_rng_next(&rng) % n);
            buf[at] = alphabet[test_rng_next(&rng) % (sizeof(alphabet) - 1)];
        }
        size_t len = n - (size_t)(test_rng_next(&rng) % 8);
        meso_skeleton s;
        meso_error err;
        memset(&err, 0, sizeof(err));
        meso_result r = meso_skeleton_parse_swc(buf, len, &s, &err);
        if (r == MESO_OK) {
            ++ok;
            for (uint32_t i = 0; i < s.node_count; ++i)
                assert(s.nodes[i].radius >= 0 && isfinite(s.nodes[i].pos[0]));
        } else {
            ++bad;
            assert((err.code >= MESO_SKEL_ISSUE_EMPTY && err.code <= MESO_SKEL_ISSUE_UNREADABLE) ||
                   err.code == MESO_SKEL_ISSUE_OUT_OF_RANGE);
            assert(strstr(err.message, "swc"));
        }
        meso_skeleton_free(&s);
    }
    fprintf(stderr, "    mutated inputs: %u parsed, %u refused with a code\n", ok, bad);
    free(buf);
}

/* The text format's optional twist=DEG (skeleton_swc.h): anywhere on the
 * line, with or without a parent; every malformed value is E3304 naming
 * the line. */
static void test_text_twist(void)
{
    const char* text = "0 0 0 0.2\n"
                       "0 1 0 0.2 twist=90\n"
                       "twist=-1.5e1 1 2 0 0.15\n"
                       "-1 2 0 0.1 2 twist=0   # a branch from node 2, explicitly untwisted\n"
                       "5 5 5 0.1 0\n";
    meso_skeleton s;
    meso_error err = {0};
    assert(meso_skeleton_parse(text, strlen(text), MESO_SKELETON_TEXT, &s, &err) == MESO_OK);
    assert(s.node_count == 5 && s.root_count == 2);
    assert(!s.nodes[0].has_twist && s.nodes[1].has_twist && s.nodes[1].twist_deg == 90);
    assert(s.nodes[2].has_twist && s.nodes[2].twist_deg == -15 && s.nodes[2].pos[0] == 1 && s.nodes[2].parent == 1);
    assert(s.nodes[3].has_twist && s.nodes[3].twist_deg == 0 && s.nodes[3].parent == 1);
    assert(!s.nodes[4].has_twist && s.nodes[4].parent == -1);
    meso_skeleton_free(&s);
    const bad_case cases[] = {
        {"0 0 0 1\n0 1 0 1 twist=\n", MESO_SKEL_ISSUE_TWIST, "line 2", "twist="},
        {"0 0 0 1\n0 1 0 1 twist=ten\n", MESO_SKEL_ISSUE_TWIST, "line 2", "'twist=ten'"},
        {"0 0 0 1\n\n0 1 0 1 twist=45deg\n", MESO_SKEL_ISSUE_TWIST, "line 3", "45deg"},
        {"0 0 0 1\n0 1 0 1 twist=nan\n", MESO_SKEL_ISSUE_TWIST, "line 2", "finite"},
        {"0 0 0 1\n0 1 0 1 twist=-inf\n", MESO_SKEL_ISSUE_TWIST, "line 2", "finite"},
        {"0 0 0 1\n0 1 0 1 twist=360001\n", MESO_SKEL_ISSUE_TWIST, "line 2", "360000"},
        {"0 0 0 1\n0 1 0 1 twist=1 twist=2\n", MESO_SKEL_ISSUE_TWIST, "line 2", "second"},
        {"0 0 0 1 twist=5\n0 1 0 1\n", MESO_SKEL_ISSUE_TWIST, "line 1", "root"},
        {"0 0 0 1\n0 1 0 1 0 twist=5\n", MESO_SKEL_ISSUE_TWIST, "line 2", "root"},
        {"0 0 0 1\n0 1 0 twist=5\n", MESO_SKEL_ISSUE_FIELD_COUNT, "line 2", "3 fields"},
        {"0 0 0 1\n0 1 0 1 1 1 1 1 twist=5\n", MESO_SKEL_ISSUE_FIELD_COUNT, "line 2", "9 fields"},
        {"0 0 0 1\n0 1 0 1 Twist=5\n", MESO_SKEL_ISSUE_NOT_A_NUMBER, "line 2", "parent"},
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); ++i) {
        memset(&err, 0, sizeof(err));
        meso_result r = meso_skeleton_parse(cases[i].text, strlen(cases[i].text), MESO_SKELETON_TEXT, &s, &err);
        fprintf(stderr, "    E%u %s\n", err.code, err.message);
        assert(r == MESO_ERR_CORRUPT && err.code == cases[i].code);
        assert(strstr(err.message, cases[i].needle));
        assert(!cases[i].needle2 || strstr(err.message, cases[i].needle2));
        assert(s.node_count == 0 && s.nodes == NULL);
    }
    /* SWC has no twist field: the token is an eighth field. */
    assert(parse("1 1 0 0 0 1 -1\n2 1 0 1 0 1 1 twist=5\n", &s, &err) == MESO_ERR_CORRUPT &&
           err.code == MESO_SKEL_ISSUE_FIELD_COUNT);
}

int main(void)
{
    TEST_RUN(test_valid);
    TEST_RUN(test_files);
    TEST_RUN(test_errors);
    TEST_RUN(test_drawable);
    TEST_RUN(test_text_twist);
    TEST_RUN(test_mutations);
    return 0;
}
