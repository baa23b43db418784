// radiosity/transfer/receiver.h - forwarding header, kept only while other files still include
// it: the transfer pipeline of paper section 5 is radiosity/transfer/transfer.h (one header per
// stage). Include that instead; this header goes once no file includes it.
#pragma once

#include "radiosity/transfer/transfer.h"
