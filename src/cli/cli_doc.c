/* The bash completion script and the karst(1) man page, both generated from the command table,
 * that is from the same usage texts that `karst help COMMAND` prints (help2man's approach: the
 * help text is the single source). Options are read from each usage text: its synopsis (the
 * text up to the first blank line: "-o DIR", "[--seed S]", "[--format table|csv|json]") and its
 * option lines ("  --seed S     base seed ..."; an option followed by one space takes the next
 * word as its value, one followed by two or more spaces takes none). */
#include <ctype.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

/* Most options one command documents, and the longest option or value name kept. */
#define DOC_MAX_OPTIONS 64
#define DOC_NAME_MAX 48
#define DOC_WORDS_MAX 160

/* What a value or a positional argument is, for completion. */
typedef enum {
  DOC_NONE,    /* nothing to complete: a number, a seed, a box, a CRS */
  DOC_FILE,    /* a file name, optionally with an extension */
  DOC_DIR,     /* a directory */
  DOC_WORDS,   /* one of fixed words ("table|csv|json", "bash") */
  DOC_COMMAND, /* a karst command */
} doc_kind_t;

typedef struct {
  doc_kind_t kind;
  char ext[16];              /* DOC_FILE: extension without the dot, or "" */
  char words[DOC_WORDS_MAX]; /* DOC_WORDS: space-separated */
} doc_value_t;

typedef struct {
  char name[DOC_NAME_MAX];
  int takes_value;
  doc_value_t value;
} doc_option_t;

typedef struct {
  int n_options;
  doc_option_t options[DOC_MAX_OPTIONS];
  int has_positional;
  doc_value_t positional; /* the first positional argument of the synopsis */
} doc_command_t;

/* Classify a metavariable ("DIR", "SCENARIO.yaml...", "table|csv|json]", "N") of length n. */
static void classify(const char *s, size_t n, doc_value_t *v) {
  char m[DOC_WORDS_MAX];
  memset(v, 0, sizeof *v);
  while (n > 0 && (*s == '[' || *s == '<'))
    s++, n--;
  while (n > 0 && strchr("].>", s[n - 1]))
    n--; /* "FILE...]" -> "FILE" */
  if (n == 0 || n >= sizeof m) return;
  memcpy(m, s, n);
  m[n] = '\0';
  int upper = 0, lower = 0, digit = 0, other = 0;
  for (const char *c = m; *c; c++) {
    if (isupper((unsigned char)*c))
      upper++;
    else if (islower((unsigned char)*c))
      lower++;
    else if (isdigit((unsigned char)*c))
      digit++;
    else if (!strchr("|_-", *c))
      other++;
  }
  const char *dot = strrchr(m, '.');
  if (strcmp(m, "COMMAND") == 0) {
    v->kind = DOC_COMMAND;
  } else if (lower && !upper && !digit && !other && !dot) {
    /* Lower-case words are literal: "bash", "table|csv|json". */
    v->kind = DOC_WORDS;
    for (char *c = m; *c; c++)
      if (*c == '|') *c = ' ';
    snprintf(v->words, sizeof v->words, "%s", m);
  } else if (dot && dot[1] && isalpha((unsigned char)dot[1])) {
    /* "SCENARIO.yaml", "cave.vtp", "OUT.gpkg": a file with that extension. */
    v->kind = DOC_FILE;
    snprintf(v->ext, sizeof v->ext, "%s", dot + 1);
  } else if (n >= 3 && strcmp(m + n - 3, "DIR") == 0) {
    v->kind = DOC_DIR;
  } else if (upper > 1 && !lower && !digit && !strchr(m, ',') &&
             (strstr(m, "FILE") || strcmp(m, "OUT") == 0 || strcmp(m, "CSV") == 0 ||
              strcmp(m, "SOURCE") == 0)) {
    v->kind = DOC_FILE;
  } else {
    v->kind = DOC_NONE; /* N, S, THREADS, 0.5, x0,y0,..., CRS */
  }
}

static int is_option(const char *s, size_t n) {
  size_t i = 0;
  while (i < n && s[i] == '[')
    i++;
  return n - i >= 2 && s[i] == '-' && (isalpha((unsigned char)s[i + 1]) || s[i + 1] == '-');
}

static doc_option_t *find_option(doc_command_t *d, const char *name, size_t n) {
  for (int i = 0; i < d->n_options; i++)
    if (strlen(d->options[i].name) == n && strncmp(d->options[i].name, name, n) == 0)
      return &d->options[i];
  if (d->n_options == DOC_MAX_OPTIONS || n >= DOC_NAME_MAX) return NULL;
  doc_option_t *o = &d->options[d->n_options++];
  memset(o, 0, sizeof *o);
  memcpy(o->name, name, n);
  return o;
}

/* The option token s[0..n) without brackets: sets *name and its length. */
static void option_name(const char *s, size_t n, const char **name, size_t *len) {
  while (n > 0 && *s == '[')
    s++, n--;
  size_t k = 0;
  while (k < n && (isalnum((unsigned char)s[k]) || s[k] == '-' || s[k] == '_'))
    k++;
  *name = s;
  *len = k;
}

/* Read the options and the first positional argument of one usage text. */
static void parse_usage(const cli_command_t *c, doc_command_t *d) {
  memset(d, 0, sizeof *d);
  const char *u = c->usage, *end = strstr(u, "\n\n");
  if (!end) end = u + strlen(u);
  /* Synopsis: skip "usage: karst NAME". */
  const char *p = strstr(u, c->name);
  p = p && p < end ? p + strlen(c->name) : end;
  const char *tok[256];
  size_t len[256];
  int nt = 0;
  while (p < end && nt < 256) {
    while (p < end && (isspace((unsigned char)*p) || *p == '|'))
      p++;
    if (p >= end) break;
    const char *q = p;
    while (q < end && !isspace((unsigned char)*q))
      q++;
    tok[nt] = p;
    len[nt++] = (size_t)(q - p);
    p = q;
  }
  for (int i = 0; i < nt; i++) {
    if (is_option(tok[i], len[i])) {
      const char *name;
      size_t nl;
      option_name(tok[i], len[i], &name, &nl);
      doc_option_t *o = find_option(d, name, nl);
      int closed = tok[i][len[i] - 1] == ']';
      if (o && !closed && i + 1 < nt && tok[i + 1][0] != '-' && tok[i + 1][0] != '[') {
        o->takes_value = 1;
        classify(tok[i + 1], len[i + 1], &o->value);
        i++;
      }
    } else if (!d->has_positional) {
      d->has_positional = 1;
      classify(tok[i], len[i], &d->positional);
    }
  }
  /* Option lines of the body: "  --seed S     text" or "  --samples    text". */
  for (const char *line = end; *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : "") {
    const char *s = line;
    if (*s == '\n') continue;
    int indent = 0;
    while (*s == ' ')
      s++, indent++;
    if (indent < 2 || *s != '-') continue;
    const char *e = s;
    while (*e && !isspace((unsigned char)*e) && *e != ',')
      e++;
    if (!is_option(s, (size_t)(e - s))) continue;
    const char *name;
    size_t nl;
    option_name(s, (size_t)(e - s), &name, &nl);
    if (nl != (size_t)(e - s)) continue;
    doc_option_t *o = find_option(d, name, nl);
    if (!o) continue;
    if (e[0] == ' ' && e[1] && !isspace((unsigned char)e[1])) {
      const char *v = e + 1, *ve = v;
      while (*ve && !isspace((unsigned char)*ve))
        ve++;
      if (!o->takes_value) classify(v, (size_t)(ve - v), &o->value);
      o->takes_value = 1;
    }
  }
}

/* ------------------------------------------------------------------------ */
/* bash                                                                      */
/* ------------------------------------------------------------------------ */

/* The compgen call that completes a value of kind @p v (the word being completed is $cur). */
static void bash_value(FILE *fp, const doc_value_t *v, const char *indent) {
  switch (v->kind) {
  case DOC_FILE:
    if (v->ext[0])
      fprintf(fp, "%sCOMPREPLY=($(compgen -f -X '!*.%s' -- \"$cur\") $(compgen -d -- \"$cur\"))\n",
              indent, v->ext);
    else
      fprintf(fp, "%sCOMPREPLY=($(compgen -f -- \"$cur\"))\n", indent);
    break;
  case DOC_DIR:
    fprintf(fp, "%sCOMPREPLY=($(compgen -d -- \"$cur\"))\n", indent);
    break;
  case DOC_WORDS:
    fprintf(fp, "%sCOMPREPLY=($(compgen -W '%s' -- \"$cur\"))\n", indent, v->words);
    break;
  case DOC_COMMAND:
    fprintf(fp, "%sCOMPREPLY=($(compgen -W \"$commands\" -- \"$cur\"))\n", indent);
    break;
  case DOC_NONE:
    fprintf(fp, "%sCOMPREPLY=()\n", indent);
    break;
  }
}

/**
 * Write a bash completion script for every command of the table: command names, each
 * command's options, and the values of options and arguments (files with the extension the
 * usage names, directories, fixed words). Source it, or install it as
 * share/bash-completion/completions/karst.
 */
void cli_doc_bash_completion(FILE *fp) {
  size_t n;
  const cli_command_t *const *cmds = cli_commands(&n);
  fprintf(fp,
          "# bash completion for karst %s, generated by `karst completion bash` from the\n"
          "# command table of `karst --help` (do not edit: regenerate it).\n"
          "_karst() {\n"
          "  local cur=${COMP_WORDS[COMP_CWORD]} prev=${COMP_WORDS[COMP_CWORD-1]}\n"
          "  local commands='",
          karst_version());
  for (size_t i = 0; i < n; i++)
    fprintf(fp, "%s%s", i ? " " : "", cmds[i]->name);
  fputs("'\n"
        "  if [ \"$COMP_CWORD\" -eq 1 ]; then\n"
        "    COMPREPLY=($(compgen -W \"$commands --help --version\" -- \"$cur\"))\n"
        "    return 0\n"
        "  fi\n"
        "  case ${COMP_WORDS[1]} in\n",
        fp);
  for (size_t i = 0; i < n; i++) {
    doc_command_t d;
    parse_usage(cmds[i], &d);
    fprintf(fp, "  %s)\n", cmds[i]->name);
    int any_value = 0;
    for (int k = 0; k < d.n_options; k++)
      any_value |= d.options[k].takes_value;
    if (any_value) {
      fputs("    case $prev in\n", fp);
      for (int k = 0; k < d.n_options; k++) {
        if (!d.options[k].takes_value) continue;
        fprintf(fp, "    %s)\n", d.options[k].name);
        bash_value(fp, &d.options[k].value, "      ");
        fputs("      return 0 ;;\n", fp);
      }
      fputs("    esac\n", fp);
    }
    fputs("    if [[ $cur == -* ]]; then\n      COMPREPLY=($(compgen -W '--help", fp);
    for (int k = 0; k < d.n_options; k++)
      if (strcmp(d.options[k].name, "--help") != 0) fprintf(fp, " %s", d.options[k].name);
    fputs("' -- \"$cur\"))\n      return 0\n    fi\n", fp);
    if (d.has_positional) {
      bash_value(fp, &d.positional, "    ");
    } else {
      fputs("    COMPREPLY=()\n", fp);
    }
    fputs("    ;;\n", fp);
  }
  fputs("  esac\n"
        "  return 0\n"
        "}\n"
        "complete -o filenames -F _karst karst\n",
        fp);
}

/* ------------------------------------------------------------------------ */
/* man page                                                                  */
/* ------------------------------------------------------------------------ */

/* Write @p s as roff text: backslashes escaped, '-' as the minus sign "\-" (so options copy
 * and search as typed), a leading '.' or '\'' protected. */
static void roff(FILE *fp, const char *s) {
  int bol = 1;
  for (; *s; s++) {
    if (bol && (*s == '.' || *s == '\'')) fputs("\\&", fp);
    bol = *s == '\n';
    if (*s == '\\')
      fputs("\\e", fp);
    else if (*s == '-')
      fputs("\\-", fp);
    else
      fputc(*s, fp);
  }
}

/**
 * Write the karst(1) man page in roff (man macros): name, synopsis, the description of
 * `karst --help`, one subsection per command holding its summary and its usage text exactly
 * as `karst help COMMAND` prints it, exit status, environment and files. The build runs this
 * to make karst.1; `cmake --install` puts it in share/man/man1.
 */
void cli_doc_man(FILE *fp) {
  size_t n;
  const cli_command_t *const *cmds = cli_commands(&n);
  fprintf(fp, ".\\\" karst(1), generated by `karst help --man` from the command table.\n");
  fprintf(fp, ".TH KARST 1 \"\" \"karst %s\" \"User Commands\"\n", karst_version());
  fputs(".SH NAME\nkarst \\- generate 3\\-D karst cave networks from geology and measure "
        "networks and cave surveys\n",
        fp);
  fputs(".SH SYNOPSIS\n.B karst\n[\\-\\-version] [\\-\\-help]\n.I COMMAND\n[\n.I ARGS\n]\n", fp);
  fputs(".SH DESCRIPTION\n", fp);
  roff(fp, cli_description);
  fputs(".PP\nThe commands, in the order of the pipeline:\n", fp);
  for (size_t i = 1; i < n; i++) {
    fprintf(fp, ".TP\n.B %s\n", cmds[i]->name);
    roff(fp, cmds[i]->summary);
    fputc('\n', fp);
  }
  fputs(".SH COMMANDS\n", fp);
  for (size_t i = 0; i < n; i++) {
    fprintf(fp, ".SS \"karst %s\"\n", cmds[i]->name);
    roff(fp, cmds[i]->summary);
    fputs(".\n.PP\n.nf\n", fp);
    roff(fp, cmds[i]->usage);
    fputs(".fi\n", fp);
  }
  fputs(".SH \"EXIT STATUS\"\n0 on success, 1 when an error occurred (the message names the "
        "file, line and field), 2 for a usage error.\n",
        fp);
  fputs(".SH ENVIRONMENT\n.TP\n.B KARST_DATA_DIR\na directory holding "
        "published_metrics.csv, the table of the 34 caves of Collon et al. 2017 (otherwise the "
        "source tree, the installed share/karst and ./datasets are searched).\n",
        fp);
  fputs(".SH \"SEE ALSO\"\nThe documentation in docs/ of the source tree: scenario.md, "
        "generation.md, metrics.md, ensembles.md, geometry.md, gis.md and python.md.\n"
        "Shell completion: \\fBkarst completion bash\\fR.\n",
        fp);
}
