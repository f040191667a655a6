// Linear mixed models: the formula language (a subset of lme4's) and the numeric expressions a
// formula may hold (`log(y)`, `I(x^2)`, `scale(x)`), parsed, printed as R deparses them and
// evaluated. Hand-written: no Debian-packaged C++ library parses R's formula language.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <set>
#include <stdexcept>

#include "hapticlab/core/diagnostics.hpp"
#include "lmm_design.hpp"

namespace hapticlab::stats {
namespace {

// A malformed expression inside the parser; ParseExpr turns it into an InputError naming the
// formula's source.
struct ExprError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string Strip(const std::string& s) {
  std::string o;
  for (char c : s)
    if (!std::isspace(static_cast<unsigned char>(c))) o += c;
  return o;
}

// Splits at any of `seps` outside parentheses; with `keep`, each piece after the first starts
// with its separator.
std::vector<std::string> SplitTop(const std::string& s, const std::string& seps,
                                  bool keep = false) {
  std::vector<std::string> out;
  int depth = 0;
  std::string cur;
  for (char c : s) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (depth == 0 && seps.find(c) != std::string::npos) {
      out.push_back(cur);
      cur = keep ? std::string(1, c) : std::string();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

bool ValidName(const std::string& s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.')) return false;
  return true;
}

// ---- numeric expressions -------------------------------------------------------------------

const std::set<std::string> kFunctions{"log", "exp", "sqrt", "scale", "I", "abs", "log10", "log2"};

struct Node {
  char op = 0;       // 0: leaf; + - * / ^ binary; 'u' unary minus; 'f' function; '(' group
  std::string text;  // leaf: column name or number; 'f': function name
  bool number = false;
  std::vector<std::unique_ptr<Node>> kids;
};

class ExprParser {
 public:
  explicit ExprParser(const std::string& s) : s_(Strip(s)) {}
  std::unique_ptr<Node> Parse() {
    auto n = Sum();
    if (pos_ != s_.size()) throw ExprError("unexpected '" + s_.substr(pos_) + "'");
    return n;
  }

 private:
  bool Eat(char c) {
    if (pos_ < s_.size() && s_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  static std::unique_ptr<Node> Binary(char op, std::unique_ptr<Node> a, std::unique_ptr<Node> b) {
    auto n = std::make_unique<Node>();
    n->op = op;
    n->kids.push_back(std::move(a));
    n->kids.push_back(std::move(b));
    return n;
  }
  std::unique_ptr<Node> Sum() {
    auto a = Product();
    for (;;) {
      if (Eat('+'))
        a = Binary('+', std::move(a), Product());
      else if (Eat('-'))
        a = Binary('-', std::move(a), Product());
      else
        return a;
    }
  }
  std::unique_ptr<Node> Product() {
    auto a = Unary();
    for (;;) {
      if (Eat('*'))
        a = Binary('*', std::move(a), Unary());
      else if (Eat('/'))
        a = Binary('/', std::move(a), Unary());
      else
        return a;
    }
  }
  std::unique_ptr<Node> Unary() {  // as R: -x^2 is -(x^2)
    if (Eat('-')) {
      auto n = std::make_unique<Node>();
      n->op = 'u';
      n->kids.push_back(Unary());
      return n;
    }
    auto a = Atom();
    if (Eat('^')) return Binary('^', std::move(a), Unary());
    return a;
  }
  std::unique_ptr<Node> Atom() {
    auto n = std::make_unique<Node>();
    if (Eat('(')) {
      n->op = '(';
      n->kids.push_back(Sum());
      if (!Eat(')')) throw ExprError("missing ')'");
      return n;
    }
    const std::size_t start = pos_;
    if (pos_ < s_.size() &&
        (std::isdigit(static_cast<unsigned char>(s_[pos_])) || s_[pos_] == '.')) {
      const char* b = s_.c_str() + pos_;
      char* end = nullptr;
      std::strtod(b, &end);
      if (end == b) throw ExprError("expected a number");
      pos_ += static_cast<std::size_t>(end - b);
      n->text = s_.substr(start, pos_ - start);
      n->number = true;
      return n;
    }
    while (pos_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[pos_])) ||
                                s_[pos_] == '_' || s_[pos_] == '.'))
      ++pos_;
    n->text = s_.substr(start, pos_ - start);
    if (!ValidName(n->text))
      throw ExprError(pos_ < s_.size() ? "unexpected '" + s_.substr(pos_) + "'"
                                       : "expression ends early");
    if (Eat('(')) {
      if (!kFunctions.count(n->text))
        throw ExprError("function '" + n->text +
                        "' is not supported (log, exp, sqrt, scale, I, abs, log10, "
                        "log2 are)");
      n->op = 'f';
      n->kids.push_back(Sum());
      if (!Eat(')')) throw ExprError("missing ')' after " + n->text + "(");
    }
    return n;
  }
  std::string s_;
  std::size_t pos_ = 0;
};

// As R's deparse: spaces around + - *, none around / ^.
std::string Deparse(const Node& n) {
  switch (n.op) {
    case 0:
      return n.text;
    case 'u':
      return "-" + Deparse(*n.kids[0]);
    case '(':
      return "(" + Deparse(*n.kids[0]) + ")";
    case 'f':
      return n.text + "(" + Deparse(*n.kids[0]) + ")";
    case '/':
    case '^':
      return Deparse(*n.kids[0]) + n.op + Deparse(*n.kids[1]);
    default:
      return Deparse(*n.kids[0]) + " " + n.op + " " + Deparse(*n.kids[1]);
  }
}

void Leaves(const Node& n, std::vector<std::string>& out) {
  if (n.op == 0 && !n.number && std::find(out.begin(), out.end(), n.text) == out.end())
    out.push_back(n.text);
  for (const auto& k : n.kids) Leaves(*k, out);
}

Eigen::VectorXd Eval(const Node& n, const detail::ColumnLookup& column) {
  if (n.op == 0) {
    if (!n.number) return column(n.text);
    Eigen::VectorXd v = column("");
    return v.setConstant(std::strtod(n.text.c_str(), nullptr));
  }
  Eigen::VectorXd a = Eval(*n.kids[0], column);
  switch (n.op) {
    case 'u':
      return -a;
    case '(':
      return a;
    case 'f':
      if (n.text == "log") return a.array().log();
      if (n.text == "log10") return a.array().log10();
      if (n.text == "log2") return a.array().log() / std::log(2.0);
      if (n.text == "exp") return a.array().exp();
      if (n.text == "sqrt") return a.array().sqrt();
      if (n.text == "abs") return a.array().abs();
      if (n.text == "scale") {  // R's scale(): centred, divided by the SD (n - 1)
        const double mean = a.mean();
        const double sd = std::sqrt((a.array() - mean).square().sum() /
                                    static_cast<double>(std::max<Eigen::Index>(a.size() - 1, 1)));
        return (a.array() - mean) / sd;
      }
      return a;  // I()
    default:
      break;
  }
  const Eigen::VectorXd b = Eval(*n.kids[1], column);
  switch (n.op) {
    case '+':
      return a + b;
    case '-':
      return a - b;
    case '*':
      return a.cwiseProduct(b);
    case '/':
      return a.cwiseQuotient(b);
    default:
      return a.array().pow(b.array());
  }
}

std::unique_ptr<Node> ParseExpr(const std::string& text, const std::string& source) {
  try {
    return ExprParser(text).Parse();
  } catch (const ExprError& e) {
    throw InputError(source, 0, "formula", "cannot read '" + text + "': " + e.what());
  }
}

// A formula variable: a column name, or a function call such as log(x) or I(x^2), printed as
// R prints it. Arithmetic outside a function is formula syntax, not arithmetic: refused.
std::string Variable(const std::string& v, const std::string& piece, const std::string& source) {
  if (ValidName(v)) return v;
  if (v.rfind("poly(", 0) == 0 && v.back() == ')') {  // poly(x, k): orthogonal polynomials
    const auto args = SplitTop(v.substr(5, v.size() - 6), ",");
    char* end = nullptr;
    const long k = args.size() == 2 ? std::strtol(args[1].c_str(), &end, 10) : 0;
    if (args.size() != 2 || args[1].empty() || *end != '\0' || k < 1 || k > 10)
      throw InputError(source, 0, "formula",
                       "expected poly(x, degree) with degree 1 to 10, got '" + v + "'");
    return "poly(" + Deparse(*ParseExpr(args[0], source)) + ", " + std::to_string(k) + ")";
  }
  const auto n = ParseExpr(v, source);
  if (n->op != 'f')
    throw InputError(source, 0, "formula",
                     "expected a column name or a function such as log(x) or I(x^2), got '" + v +
                         "' in '" + piece + "' (write arithmetic inside I())");
  return Deparse(*n);
}

// "a*b:c" -> terms a, b:c, a:b:c ("*" expands to all interactions of its operands).
void AddTerms(const std::string& piece, std::vector<std::vector<std::string>>& terms,
              const std::string& source) {
  std::vector<std::vector<std::string>> ops;
  for (const auto& f : SplitTop(piece, "*")) {
    std::vector<std::string> vars;
    for (const auto& v : SplitTop(f, ":")) vars.push_back(Variable(v, piece, source));
    ops.push_back(vars);
  }
  const std::size_t m = ops.size();
  for (std::size_t mask = 1; mask < (std::size_t{1} << m); ++mask) {
    std::vector<std::string> t;
    for (std::size_t i = 0; i < m; ++i)
      if (mask & (std::size_t{1} << i)) t.insert(t.end(), ops[i].begin(), ops[i].end());
    terms.push_back(t);
  }
}

// Drops repeated terms (a:b equals b:a) and orders by degree, stably (as R's terms()).
void Canonical(std::vector<std::vector<std::string>>& terms) {
  std::vector<std::vector<std::string>> out;
  std::set<std::set<std::string>> seen;
  for (const auto& t : terms) {
    std::set<std::string> k(t.begin(), t.end());
    if (seen.insert(k).second) out.push_back(t);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.size() < b.size(); });
  terms = out;
}

std::string JoinColon(const std::vector<std::string>& t) {
  std::string s;
  for (const auto& v : t) s += (s.empty() ? "" : ":") + v;
  return s;
}

// The grouping factors after '|': "g", "a:b" (their interaction), "a/b" (nesting: lme4 makes
// the terms b:a and a, most nested first).
std::vector<std::vector<std::string>> Groups(const std::string& spec, const std::string& piece,
                                             const std::string& source) {
  std::vector<std::vector<std::string>> levels;  // a/b/c: [a], [b], [c]
  for (const auto& part : SplitTop(spec, "/")) {
    std::vector<std::string> f;
    for (const auto& v : SplitTop(part, ":")) {
      if (!ValidName(v))
        throw InputError(source, 0, "formula",
                         "expected grouping columns after '|' (g, a:b or a/b) in '" + piece + "'");
      f.push_back(v);
    }
    levels.push_back(f);
  }
  std::vector<std::vector<std::string>> out;
  for (std::size_t k = levels.size(); k-- > 0;) {
    std::vector<std::string> g;
    for (std::size_t i = k + 1; i-- > 0;) g.insert(g.end(), levels[i].begin(), levels[i].end());
    out.push_back(g);
  }
  return out;
}

// "(1 + x | g)", "(x || g)", "(1 | a/b)" -> random terms (lme4's expansion of || and /).
void AddRandom(const std::string& piece, LmmFormula& f, const std::string& source) {
  if (piece.back() != ')')
    throw InputError(source, 0, "formula", "unbalanced parentheses in '" + piece + "'");
  const std::string in = piece.substr(1, piece.size() - 2);
  const auto bar = in.find('|');
  const bool uncorrelated = bar != std::string::npos && in.compare(bar, 2, "||") == 0;
  const auto after = bar + (uncorrelated ? 2 : 1);
  if (bar == std::string::npos || in.find('|', after) != std::string::npos)
    throw InputError(source, 0, "formula",
                     "expected '(terms | group)' or '(terms || group)', got '" + piece + "'");
  LmmFormula::Random r;
  bool saw_zero = false;
  for (const auto& t : SplitTop(in.substr(0, bar), "+")) {
    if (t == "1") continue;
    if (t == "0") {
      saw_zero = true;
      continue;
    }
    AddTerms(t, r.terms, source);
  }
  r.intercept = !saw_zero;
  Canonical(r.terms);
  if (!r.intercept && r.terms.empty())
    throw InputError(source, 0, "formula", "random term '" + piece + "' is empty");
  for (const auto& g : Groups(in.substr(after), piece, source)) {
    r.group_factors = g;
    r.group = JoinColon(g);
    if (!uncorrelated) {
      f.random.push_back(r);
      continue;
    }
    // lme4's ||: (1 | g) and one (0 + term | g) per term, each with its own covariance.
    if (r.intercept) f.random.push_back({true, {}, r.group, g});
    for (const auto& t : r.terms) f.random.push_back({false, {t}, r.group, g});
  }
}

}  // namespace

namespace detail {

bool IsColumnName(const std::string& label) { return ValidName(label); }

bool PolyLabel(const std::string& label, std::string& inner, int& degree) {
  if (label.rfind("poly(", 0) != 0) return false;
  const auto comma = label.rfind(", ");
  inner = label.substr(5, comma - 5);
  degree = std::atoi(label.c_str() + comma + 2);
  return true;
}

std::vector<std::string> ExprColumns(const std::string& label) {
  std::vector<std::string> out;
  if (ValidName(label)) return {label};
  std::string inner;
  int degree = 0;
  Leaves(*ParseExpr(PolyLabel(label, inner, degree) ? inner : label, ""), out);
  return out;
}

Eigen::VectorXd EvalExpr(const std::string& label, const ColumnLookup& column) {
  return Eval(*ParseExpr(label, ""), column);
}

}  // namespace detail

std::vector<std::string> LmmFormula::Columns() const {
  std::vector<std::string> c{response};
  auto add = [&](const std::string& label) {
    for (const auto& v : detail::ExprColumns(label))
      if (std::find(c.begin(), c.end(), v) == c.end()) c.push_back(v);
  };
  for (const auto& t : fixed)
    for (const auto& v : t) add(v);
  for (const auto& r : random) {
    for (const auto& t : r.terms)
      for (const auto& v : t) add(v);
    for (const auto& g : r.group_factors) add(g);
  }
  return c;
}

LmmFormula ParseLmmFormula(const std::string& formula, const std::string& source) {
  const std::string s = Strip(formula);
  const auto tilde = s.find('~');
  if (tilde == std::string::npos || s.find('~', tilde + 1) != std::string::npos)
    throw InputError(source, 0, "formula", "expected 'response ~ terms', got '" + formula + "'");
  LmmFormula f;
  if (tilde == 0) throw InputError(source, 0, "formula", "expected a response before '~'");
  f.response_term = Variable(s.substr(0, tilde), s.substr(0, tilde), source);
  const auto cols = detail::ExprColumns(f.response_term);
  if (cols.size() != 1)
    throw InputError(source, 0, "formula",
                     "the response '" + f.response_term + "' must use exactly one column");
  f.response = cols[0];
  if (f.response_term.rfind("poly(", 0) == 0)
    throw InputError(source, 0, "formula", "poly() is for predictors, not the response");
  const auto pieces = SplitTop(s.substr(tilde + 1), "+-", true);
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const std::string& signed_piece = pieces[i];
    if (i == 0 && signed_piece.empty() && pieces.size() > 1) continue;  // y ~ -1 + x
    const bool minus = !signed_piece.empty() && signed_piece[0] == '-';
    const std::string piece =
        !signed_piece.empty() && (signed_piece[0] == '-' || signed_piece[0] == '+')
            ? signed_piece.substr(1)
            : signed_piece;
    if (piece.empty()) throw InputError(source, 0, "formula", "empty term in '" + formula + "'");
    if (piece == "1" || piece == "0") {  // y ~ 0 + x, y ~ x - 1, y ~ 1 + x
      f.intercept = (piece == "1") != minus;
    } else if (minus) {
      throw InputError(source, 0, "formula",
                       "'- " + piece + "': only '- 1' (no intercept) may be removed with '-'");
    } else if (piece.front() == '(') {
      AddRandom(piece, f, source);
    } else {
      AddTerms(piece, f.fixed, source);
    }
  }
  if (f.random.empty())
    throw InputError(
        source, 0, "formula",
        "no random term such as '(1 | participant)': use rm-anova for a fixed-effects model");
  Canonical(f.fixed);
  if (!f.intercept && f.fixed.empty())
    throw InputError(source, 0, "formula", "the fixed part has no term and no intercept");
  return f;
}

}  // namespace hapticlab::stats
