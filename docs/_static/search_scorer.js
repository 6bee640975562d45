/* mechsys: the scores of Sphinx's search (searchtools.js) with one change: the decision
   records (decisions/) sink below every other page, so that a search for "reaction force"
   lists the guides and the API first; they stay findable at the end of the list. */
var Scorer = {
  score: (result) => {
    const [docname, , , , score] = result;
    return docname.startsWith("decisions/") ? score - 1000 : score;
  },
  objNameMatch: 11,
  objPartialMatch: 6,
  objPrio: { 0: 15, 1: 5, 2: -5 },
  objPrioDefault: 0,
  title: 15,
  partialTitle: 7,
  term: 5,
  partialTerm: 2,
};
