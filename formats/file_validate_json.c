/*
 * file_validate_json.c — the META and RPRT chunks' text rules (FORMAT.md
 * §7.1): valid UTF-8 (no overlong forms, no surrogates, nothing above
 * U+10FFFF) and strict RFC 8259 JSON, one value, nesting depth <= 64.
 * Written here rather than taken from cJSON (which the format library must
 * not depend on, and which accepts more than RFC 8259). Nothing allocates.
 */
#include "file_internal.h"

/* Strict RFC 8259 syntax check over bytes already known to be UTF-8. Depth
 * is limited so hostile nesting cannot exhaust the stack. */
#define JSON_MAX_DEPTH 64

typedef struct json_state {
    const uint8_t* begin;
    const uint8_t* p;
    const uint8_t* end;
    uint32_t code; /* issue on failure */
    const char* what;
} json_state;

static int json_fail(json_state* j, uint32_t code, const char* what)
{
    j->code = code;
    j->what = what;
    return 0;
}

static void json_ws(json_state* j)
{
    while (j->p < j->end && (*j->p == ' ' || *j->p == '\t' || *j->p == '\n' || *j->p == '\r'))
        j->p++;
}

static int json_lit(json_state* j, const char* s)
{
    size_t n = strlen(s);
    if ((size_t)(j->end - j->p) < n || memcmp(j->p, s, n) != 0)
        return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "invalid literal");
    j->p += n;
    return 1;
}

static int is_hex(uint8_t c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F'); }
static int is_digit(uint8_t c) { return c >= '0' && c <= '9'; }

static int json_string(json_state* j)
{
    j->p++; /* opening quote */
    while (j->p < j->end) {
        uint8_t c = *j->p++;
        if (c == '"')
            return 1;
        if (c < 0x20)
            return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "control character in string");
        if (c == '\\') {
            if (j->p >= j->end)
                break;
            c = *j->p++;
            if (c == 'u') {
                if (j->end - j->p < 4 || !is_hex(j->p[0]) || !is_hex(j->p[1]) || !is_hex(j->p[2]) || !is_hex(j->p[3]))
                    return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "bad \\u escape");
                j->p += 4;
            } else if (!strchr("\"\\/bfnrt", c) || c == 0) {
                return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "bad escape");
            }
        }
    }
    return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "unterminated string");
}

static int json_number(json_state* j)
{
    if (j->p < j->end && *j->p == '-')
        j->p++;
    if (j->p >= j->end || !is_digit(*j->p))
        return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "bad number");
    if (*j->p == '0')
        j->p++;
    else
        while (j->p < j->end && is_digit(*j->p))
            j->p++;
    if (j->p < j->end && *j->p == '.') {
        j->p++;
        if (j->p >= j->end || !is_digit(*j->p))
            return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "bad fraction");
        while (j->p < j->end && is_digit(*j->p))
            j->p++;
    }
    if (j->p < j->end && (*j->p == 'e' || *j->p == 'E')) {
        j->p++;
        if (j->p < j->end && (*j->p == '+' || *j->p == '-'))
            j->p++;
        if (j->p >= j->end || !is_digit(*j->p))
            return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "bad exponent");
        while (j->p < j->end && is_digit(*j->p))
            j->p++;
    }
    return 1;
}

static int json_value(json_state* j, int depth)
{
    json_ws(j);
    if (j->p >= j->end)
        return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "unexpected end");
    uint8_t c = *j->p;
    if (c == '{' || c == '[') {
        if (depth >= JSON_MAX_DEPTH)
            return json_fail(j, MESO_ISSUE_JSON_DEPTH, "nesting deeper than 64");
        uint8_t close = c == '{' ? '}' : ']';
        j->p++;
        json_ws(j);
        if (j->p < j->end && *j->p == close) {
            j->p++;
            return 1;
        }
        for (;;) {
            if (c == '{') {
                json_ws(j);
                if (j->p >= j->end || *j->p != '"')
                    return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "expected a string key");
                if (!json_string(j))
                    return 0;
                json_ws(j);
                if (j->p >= j->end || *j->p != ':')
                    return json_fail(j, MESO_ISSUE_JSON_SYNTAX, "expected ':'");
                j->p++;
            }
            if (!json_value(j, depth + 1))
                return 0;
            json_ws(j);
            if (j->p < j->end && *j->p == ',') {
                j->p++;
                continue;
            }
            if (j->p < j->end && *j->p == close) {
                j->p++;
                return 1;
            }
            return json_fail(j, MESO_ISSUE_JSON_SYNTAX, c == '{' ? "expected ',' or '}'" : "expected ',' or ']'");
        }
    }
    if (c == '"')
        return json_string(j);
    if (c == 't')
        return json_lit(j, "true");
    if (c == 'f')
        return json_lit(j, "false");
    if (c == 'n')
        return json_lit(j, "null");
    return json_number(j);
}

/* Offset of the first invalid UTF-8 sequence, or SIZE_MAX (RFC 3629:
 * no overlongs, no surrogates, nothing above U+10FFFF). */
size_t mesoi_utf8_invalid(const uint8_t* s, size_t n)
{
    size_t i = 0;
    while (i < n) {
        uint8_t c = s[i];
        size_t len;
        uint32_t cp;
        if (c < 0x80) {
            i++;
            continue;
        } else if (c >= 0xC2 && c <= 0xDF) {
            len = 2;
            cp = c & 0x1Fu;
        } else if (c >= 0xE0 && c <= 0xEF) {
            len = 3;
            cp = c & 0x0Fu;
        } else if (c >= 0xF0 && c <= 0xF4) {
            len = 4;
            cp = c & 0x07u;
        } else {
            return i;
        }
        if (n - i < len)
            return i;
        for (size_t k = 1; k < len; k++) {
            if ((s[i + k] & 0xC0) != 0x80)
                return i;
            cp = (cp << 6) | (s[i + k] & 0x3Fu);
        }
        if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)) || (cp >= 0xD800 && cp <= 0xDFFF))
            return i;
        i += len;
    }
    return SIZE_MAX;
}

int mesoi_json_check(const uint8_t* d, size_t n, uint32_t* code, const char** what, size_t* pos)
{
    json_state j = {d, d, d + n, 0, NULL};
    if (json_value(&j, 0)) {
        json_ws(&j);
        if (j.p == j.end)
            return 1;
        json_fail(&j, MESO_ISSUE_JSON_SYNTAX, "trailing characters after the value");
    }
    *code = j.code;
    *what = j.what;
    *pos = (size_t)(j.p - j.begin);
    return 0;
}
