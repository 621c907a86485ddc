// placeholder so that cb_problems has a source until problems/ lands
namespace cb { int problems_placeholder = 0; }
