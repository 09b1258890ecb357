/* QGIS layer styles (QML) from the shared palette (include/karst/palette.h), so that QGIS colours
 * tunnel types and node kinds as the report, the ParaView scripts and the docs do. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "karst/export.h"
#include "karst/palette.h"

/** Drawn sizes, in millimetres on the map (QGIS "MM" units): conduit lines, network nodes and
 *  key points. */
#define QML_LINE_WIDTH_MM 0.6
#define QML_NODE_SIZE_MM 1.2
#define QML_KEY_POINT_SIZE_MM 3.0

/* Write @p s with the five XML escapes. */
static void xml_text(FILE *fp, const char *s) {
  for (; *s; s++)
    switch (*s) {
    case '&':
      fputs("&amp;", fp);
      break;
    case '<':
      fputs("&lt;", fp);
      break;
    case '>':
      fputs("&gt;", fp);
      break;
    case '"':
      fputs("&quot;", fp);
      break;
    case '\'':
      fputs("&apos;", fp);
      break;
    default:
      fputc(*s, fp);
    }
}

/* One property, in both the QGIS >= 3.26 form (<Option>, inside the Map written by the caller)
 * and the older <prop> form, so that every QGIS 3 reads it. */
typedef struct {
  const char *k, *v;
} prop_t;

static void symbol_layer(FILE *fp, const char *cls, const prop_t *props, int n) {
  fprintf(fp, "        <layer class=\"%s\" enabled=\"1\" locked=\"0\" pass=\"0\">\n", cls);
  fputs("          <Option type=\"Map\">\n", fp);
  for (int i = 0; i < n; i++)
    fprintf(fp, "            <Option name=\"%s\" type=\"QString\" value=\"%s\"/>\n", props[i].k,
            props[i].v);
  fputs("          </Option>\n", fp);
  for (int i = 0; i < n; i++)
    fprintf(fp, "          <prop k=\"%s\" v=\"%s\"/>\n", props[i].k, props[i].v);
  fputs("        </layer>\n", fp);
}

/* One symbol named @p name drawn in colour @p hex ("#RRGGBB"). */
static void symbol(FILE *fp, karst_export_style_t style, const char *name, const char *hex) {
  double rgb[3] = {0.5, 0.5, 0.5};
  karst_palette_hex_rgb(hex, rgb);
  char colour[32], size[32];
  snprintf(colour, sizeof colour, "%d,%d,%d,255", (int)(rgb[0] * 255 + 0.5),
           (int)(rgb[1] * 255 + 0.5), (int)(rgb[2] * 255 + 0.5));
  if (style == KARST_EXPORT_STYLE_CONDUITS) {
    snprintf(size, sizeof size, "%g", QML_LINE_WIDTH_MM);
    const prop_t p[] = {{"line_color", colour},  {"line_width", size},  {"line_width_unit", "MM"},
                        {"line_style", "solid"}, {"capstyle", "round"}, {"joinstyle", "round"}};
    fprintf(fp,
            "      <symbol alpha=\"1\" clip_to_extent=\"1\" force_rhr=\"0\" name=\"%s\" "
            "type=\"line\">\n",
            name);
    symbol_layer(fp, "SimpleLine", p, (int)(sizeof p / sizeof p[0]));
  } else {
    snprintf(size, sizeof size, "%g",
             style == KARST_EXPORT_STYLE_NODES ? QML_NODE_SIZE_MM : QML_KEY_POINT_SIZE_MM);
    const prop_t p[] = {{"name", "circle"},
                        {"color", colour},
                        {"size", size},
                        {"size_unit", "MM"},
                        {"outline_color", "35,35,35,255"},
                        {"outline_width", "0.2"},
                        {"outline_width_unit", "MM"}};
    fprintf(fp,
            "      <symbol alpha=\"1\" clip_to_extent=\"1\" force_rhr=\"0\" name=\"%s\" "
            "type=\"marker\">\n",
            name);
    symbol_layer(fp, "SimpleMarker", p, (int)(sizeof p / sizeof p[0]));
  }
  fputs("      </symbol>\n", fp);
}

/**
 * The QML of one layer's style (see export.h): a categorised renderer on the palette entry of
 * the layer's field, tunnel_type for conduits and kind for nodes and key points, with one
 * category per palette category (its code as value, its name as label, its colour), or a
 * single symbol in the palette's survey colour (conduits) or neutral colour (points) when
 * @p categorised is 0.
 * @return malloc'ed text, NULL when out of memory. Time complexity: O(categories).
 */
char *karst_export_qml(karst_export_style_t style, int categorised) {
  const char *field = style == KARST_EXPORT_STYLE_CONDUITS ? "tunnel_type" : "kind";
  const karst_palette_t *pal = karst_palette_find(field);
  if (!pal || pal->kind != KARST_PALETTE_CATEGORICAL) categorised = 0;
  char *text = NULL;
  size_t len = 0;
  FILE *fp = open_memstream(&text, &len);
  if (!fp) return NULL;
  fputs("<!DOCTYPE qgis PUBLIC 'http://mrcc.com/qgis.dtd' 'SYSTEM'>\n"
        "<!-- Written by karst from its shared palette (include/karst/palette.h). -->\n"
        "<qgis version=\"3.22.0\" styleCategories=\"Symbology\">\n",
        fp);
  if (categorised) {
    fputs("  <renderer-v2 type=\"categorizedSymbol\" attr=\"", fp);
    xml_text(fp, field);
    fputs("\" enableorderby=\"0\" forceraster=\"0\" symbollevels=\"0\">\n    <categories>\n", fp);
    for (int i = 0; i < pal->n; i++) {
      fprintf(fp, "      <category render=\"true\" symbol=\"%d\" value=\"%d\" label=\"", i,
              pal->categories[i].code);
      xml_text(fp, pal->categories[i].name);
      fputs("\"/>\n", fp);
    }
    fputs("    </categories>\n    <symbols>\n", fp);
    for (int i = 0; i < pal->n; i++) {
      char name[16];
      snprintf(name, sizeof name, "%d", i);
      symbol(fp, style, name, pal->categories[i].hex);
    }
    fputs("    </symbols>\n", fp);
  } else {
    fputs("  <renderer-v2 type=\"singleSymbol\" enableorderby=\"0\" forceraster=\"0\" "
          "symbollevels=\"0\">\n    <symbols>\n",
          fp);
    symbol(fp, style, "0",
           karst_palette_role(style == KARST_EXPORT_STYLE_CONDUITS ? KARST_PALETTE_ROLE_SURVEY
                                                                   : KARST_PALETTE_ROLE_NONE));
    fputs("    </symbols>\n", fp);
  }
  fputs("  </renderer-v2>\n", fp);
  fprintf(fp, "  <layerGeometryType>%d</layerGeometryType>\n</qgis>\n",
          style == KARST_EXPORT_STYLE_CONDUITS ? 1 : 0);
  int bad = ferror(fp);
  if (fclose(fp) != 0 || bad) {
    free(text);
    return NULL;
  }
  return text;
}
