; TF5200 diagnosis, ID 20721 "Number of parameters and the number of format specifiers do not match.": three format elements without their values
; https://infosys.beckhoff.com/content/1033/tf5200_diagnosis/252329867.html
; adapted: the page's text is cut where the bracket closes: closed after the text; M30 appended.
; expect: error 20721
N10 #MSG ["WERT1=%D WERT2=%D WERT3=%D "]
N20 M30
